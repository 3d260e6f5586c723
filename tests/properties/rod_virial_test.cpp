// The rods' share of the virial, against the ideal gas of rigid molecules: a rotating
// dumbbell pushes on nothing by its rotation. Its rod's tension is mu v^2 / L (v the
// relative speed), so the rod's virial r . f = -mu v^2 cancels twice the rotational kinetic
// energy, and the pressure is that of the centre of mass alone, M v_c^2 / (3 V).
#include <gtest/gtest.h>

#include <cmath>

#include "integrators/gvi.hpp"
#include "simulation/run_loop.hpp"
#include "support/atoms_input.hpp"

namespace deli {
namespace {

class Pressures final : public Observer {
 public:
  void on_thermo(const ThermoSample& s) override { values.push_back(s.pressure); }
  std::vector<double> values;
};

TEST(RodVirial, RotatingDumbbellHasTheCentreOfMassPressure) {
  const Vec3 centre_velocity{0.3, 0.0, 0.2};
  RunInput input = testing::input_with_atoms(
      "dumbbell",
      {{{4.5, 5, 5}, Vec3{0, 1, 0} + centre_velocity},
       {{5.5, 5, 5}, Vec3{0, -1, 0} + centre_velocity}},
      "ppp", {0, 0, 0}, {10, 10, 10},
      "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nrods = [{ atoms = [1, 2], length = "
      "1.0 }]\n[integrator]\ntype = \"gvi\"\ntimestep = 0.001\n[run]\nsteps = 0\n");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  Pressures pressures;
  run(input.system, gvi, 2000, 1, {&pressures});
  const double volume = 1000.0;
  const double expected = 2.0 * norm2(centre_velocity) / (3.0 * volume);  // M = 2
  // Without the rod's virial the pressure would be (2 K) / (3 V), K = 1.13: 5.7 times more.
  // The discrete tension differs from mu v^2 / L by O((omega h)^2) = 4e-6 relative.
  ASSERT_GT(pressures.values.size(), 1000u);
  for (std::size_t k = 1; k < pressures.values.size(); ++k) {
    ASSERT_NEAR(pressures.values[k], expected, 1e-5 * 2.0 / (3.0 * volume)) << "sample " << k;
  }
}

}  // namespace
}  // namespace deli
