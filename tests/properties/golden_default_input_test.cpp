// The first 100 steps of the default input (inputs/lj_chains/rigid_slit.toml: GVI with
// rods, contacts, walls, shadow-H reflections, the constrained predictor, inside its
// Langevin thermostat) against tests/golden/default_input_100_steps.txt: energies every
// step and three atoms' positions and velocities, at 17 significant digits.
//
// Compared bit for bit (as text that round-trips every double): deli is IEEE-exact (no
// -ffast-math, no FMA contraction on x86-64 without -march) and its results do not depend
// on the optimisation level, so any change of a result shows here. The libm function the
// run calls (exp in the thermostat's factor; the noise's logarithm is deli's polar_log) is
// glibc's, fixed on Debian 12; on another libm the first difference would be in the last
// digits, and the failure message gives the relative size of the first difference to tell
// that from a change of method.
//
// A change of results that is intended (a new solver, a reordered sum) regenerates the file:
//   OMP_NUM_THREADS=1 DELI_GOLDEN_UPDATE=1 build/tests/deli_property_tests --gtest_filter=Golden.*
// (one thread, as ctest runs it: the pair forces' partial sums, and so the last bits,
// depend on the thread count)
// and the commit says why the numbers moved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>

#include "cli/integrator_factory.hpp"
#include "input/run_input.hpp"
#include "simulation/run_loop.hpp"

namespace deli {
namespace {

const std::string kGolden =
    std::string(DELI_SOURCE_DIR) + "/tests/golden/default_input_100_steps.txt";

std::string format(const char* pattern, auto... values) {
  char line[512];
  std::snprintf(line, sizeof line, pattern, values...);
  return line;
}

class Record final : public Observer {
 public:
  void on_thermo(const ThermoSample& s) override {
    lines.push_back(format("energy %lld %.17g %.17g %.17g", static_cast<long long>(s.step),
                           s.kinetic, s.potential, s.total));
  }
  void on_step(const System& system) override {
    // The atoms listed first, in the middle and last in the input, wherever the run's sorts
    // have put them.
    const Particles& p = system.particles;
    for (std::size_t listed : {std::size_t{0}, p.size() / 2, p.size() - 1}) {
      std::size_t i = listed;
      if (!p.origin.empty()) {
        i = static_cast<std::size_t>(
            std::find(p.origin.begin(), p.origin.end(), static_cast<std::int32_t>(listed)) -
            p.origin.begin());
      }
      lines.push_back(format("atom %lld %lld %.17g %.17g %.17g %.17g %.17g %.17g",
                             static_cast<long long>(system.step), static_cast<long long>(p.id[i]),
                             p.position[i].x, p.position[i].y, p.position[i].z, p.velocity[i].x,
                             p.velocity[i].y, p.velocity[i].z));
    }
  }
  std::vector<std::string> lines;
};

// The samples' shadow energies, for an observer that asks for them (the CSV writer's part).
class ShadowEnergies final : public Observer {
 public:
  void on_thermo(const ThermoSample& s) override { values.push_back(s.shadow_energy); }
  bool wants_shadow_energy() const override { return true; }
  std::vector<std::optional<double>> values;
};

std::vector<std::string> run_default_input(ShadowEnergies* shadow = nullptr) {
  RunInput input = load_run_input(DELI_DEFAULT_INPUT);
  const std::unique_ptr<Integrator> integrator = make_integrator(input);
  Record record;
  RunOptions options;
  options.degrees_of_freedom = input.degrees_of_freedom;
  options.start_temperature = input.start_temperature;
  std::vector<Observer*> observers = {&record};
  if (shadow) observers.push_back(shadow);
  run(input.system, *integrator, 100, 1, observers, options);
  return record.lines;
}

// The largest relative difference between the numbers of two lines of the same shape.
double relative_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string ta, tb;
  double worst = 0;
  while (sa >> ta && sb >> tb) {
    char* end = nullptr;
    const double x = std::strtod(ta.c_str(), &end), y = std::strtod(tb.c_str(), nullptr);
    if (*end != '\0' || x == y) continue;
    worst = std::max(worst, std::abs(x - y) / std::max(std::abs(x), std::abs(y)));
  }
  return worst;
}

TEST(Golden, DefaultInputFirst100StepsBitForBit) {
  const std::vector<std::string> lines = run_default_input();
  ASSERT_EQ(lines.size(), 101u + 300u);
  if (std::getenv("DELI_GOLDEN_UPDATE")) {
    std::ofstream out(kGolden);
    out << "# deli golden file: tests/properties/golden_default_input_test.cpp says how to\n"
           "# regenerate it. energy STEP KINETIC POTENTIAL TOTAL; atom STEP ID X Y Z VX VY VZ\n";
    for (const std::string& line : lines) out << line << "\n";
    ASSERT_TRUE(out.good()) << "could not write " << kGolden;
    GTEST_SKIP() << "wrote " << kGolden;
  }
  std::ifstream in(kGolden);
  ASSERT_TRUE(in.good()) << kGolden << " is missing";
  std::vector<std::string> golden;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') golden.push_back(line);
  }
  ASSERT_EQ(golden.size(), lines.size()) << kGolden;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    ASSERT_EQ(lines[k], golden[k]) << "first difference from " << kGolden << ", relative size "
                                   << relative_difference(lines[k], golden[k])
                                   << ": if the change is intended, regenerate the file (see "
                                      "the test's header) and say why in the commit";
  }
}

// The shadow energy is found only where an observer asks (the terminal's table does not
// show it), and finding it must not change the run: it reads the state and the neighbour
// list. Expected value: the same lines bit for bit, by definition of an observation; the
// default input's integrator (GVI on rods) has a shadow energy at every sample.
TEST(Golden, AskingForTheShadowEnergyLeavesTheRunAsItWas) {
  ShadowEnergies shadow;
  const std::vector<std::string> asked = run_default_input(&shadow);
  const std::vector<std::string> unasked = run_default_input();
  ASSERT_EQ(shadow.values.size(), 101u);
  for (const std::optional<double>& value : shadow.values) {
    ASSERT_TRUE(value.has_value());
    EXPECT_TRUE(std::isfinite(*value));
  }
  EXPECT_EQ(asked, unasked);
}

}  // namespace
}  // namespace deli
