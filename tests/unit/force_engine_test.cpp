#include "integrators/force_engine.hpp"

#include <gtest/gtest.h>

#include <string>

#include "input/run_input.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

// An ideal gas (no force term) on an fcc lattice of cells^3 cells.
RunInput gas(int cells) {
  const std::string n = std::to_string(cells);
  return testing::input_from(R"([system]
[system.lattice]
type = "fcc"
density = 0.5
cells = [)" + n + ", " + n + ", " +
                             n + R"(]
[forcefield.pair]
style = "none"
[integrator]
timestep = 0.005
[run]
steps = 0
)");
}

// A force field without terms: zero forces, one per particle, at every evaluation, also when
// the engine's zeros were made for another particle count (the engine zeroes them once and
// keeps that they are zeros); no energy, no term.
TEST(ForceEngine, AForceFieldWithoutTermsGivesZerosForEveryParticleAtEveryEvaluation) {
  RunInput small = gas(2), large = gas(3);
  ASSERT_TRUE(small.force_field->terms().empty());
  ForceEngine engine(*small.force_field, 0.3);
  for (RunInput* input : {&small, &small, &large, &large, &small}) {
    for (const bool tally : {false, true}) {
      const ForceEvaluation& e = engine.compute(input->system, tally);
      ASSERT_EQ(engine.force().size(), input->system.particles.size());
      for (const Vec3& f : engine.force()) {
        ASSERT_EQ(f.x, 0.0);
        ASSERT_EQ(f.y, 0.0);
        ASSERT_EQ(f.z, 0.0);
      }
      EXPECT_EQ(e.tallied, tally);
      EXPECT_EQ(e.potential, 0.0);
      EXPECT_TRUE(e.names.empty());
      EXPECT_TRUE(e.energies.empty());
    }
  }
}

}  // namespace
}  // namespace deli
