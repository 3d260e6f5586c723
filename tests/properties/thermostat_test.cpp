// Thermostats sample the canonical ensemble: the kinetic energy K of d degrees of freedom
// at temperature T is Gamma(d/2, T) distributed, mean d T / 2 and variance d T^2 / 2, and
// each kind of degree of freedom holds T / 2 (equipartition). Checked on an LJ liquid,
// rigid chains and a hard-sphere fluid with both thermostats; error bars from block
// averages of the run itself (4 standard errors).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "cli/integrator_factory.hpp"
#include "simulation/run_loop.hpp"
#include "support/block_average.hpp"
#include "support/short_runs.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

using testing::block_estimate;
using testing::Estimate;

// The variance within each block, averaged (blocks much longer than the correlation time).
Estimate block_variance(const std::vector<double>& series, int blocks = 20) {
  const std::size_t per = series.size() / static_cast<std::size_t>(blocks);
  std::vector<double> variances;
  for (int b = 0; b < blocks; ++b) {
    double sum = 0, sum2 = 0;
    for (std::size_t k = 0; k < per; ++k) {
      sum += series[b * per + k];
      sum2 += series[b * per + k] * series[b * per + k];
    }
    const double mean = sum / static_cast<double>(per);
    variances.push_back((sum2 / static_cast<double>(per) - mean * mean) * static_cast<double>(per) /
                        static_cast<double>(per - 1));
  }
  return block_estimate(variances, blocks);
}

double standard_deviation(const std::vector<double>& series) {
  return std::sqrt(testing::variance(series));
}

// Kinetic energy of each molecule's centre of mass, summed, at every sample.
class Sampler final : public Observer {
 public:
  void on_thermo(const ThermoSample& s) override {
    if (s.step <= skip_until) return;
    kinetic.push_back(s.kinetic);
    temperature.push_back(s.temperature);
    potential.push_back(s.potential);
    conserved.push_back(s.conserved.value_or(s.total));
    total.push_back(s.total);
  }
  void on_step(const System& system) override {
    if (system.step <= skip_until || system.step % every != 0) return;
    std::map<std::int64_t, std::pair<Vec3, double>> molecules;  // momentum, mass
    const Particles& p = system.particles;
    for (std::size_t i = 0; i < p.size(); ++i) {
      auto& [momentum, mass] = molecules[p.molecule[i]];
      momentum += p.velocity[i] * p.mass[i];
      mass += p.mass[i];
    }
    double sum = 0;
    for (const auto& [id, m] : molecules) sum += 0.5 * norm2(m.first) / m.second;
    centre_of_mass_kinetic.push_back(sum);
  }
  std::int64_t skip_until = 0, every = 1;
  std::vector<double> kinetic, temperature, potential, conserved, total, centre_of_mass_kinetic;
};

// Under the sanitizers (support/short_runs.hpp) a tenth of the equilibration and of the
// samples' steps, and the statistical checks below left to the plain pass.
Sampler sample(RunInput& input, std::int64_t equilibrate, std::int64_t steps, std::int64_t every) {
  if (testing::short_runs()) equilibrate /= 10, steps /= 10;
  const std::unique_ptr<Integrator> integrator = make_integrator(input);
  Sampler sampler;
  sampler.skip_until = equilibrate;
  sampler.every = every;
  RunOptions options;
  options.degrees_of_freedom = input.degrees_of_freedom;
  options.start_temperature = input.start_temperature;
  run(input.system, *integrator, equilibrate + steps, every, {&sampler}, options);
  return sampler;
}

// Sanitizer pass: every sample finite and a positive temperature, and nothing more.
bool short_run_checked(const Sampler& s, const std::string& what) {
  if (!testing::short_runs()) return false;
  EXPECT_FALSE(s.temperature.empty()) << what;
  for (const std::vector<double>* series : {&s.kinetic, &s.temperature, &s.potential, &s.conserved,
                                            &s.total, &s.centre_of_mass_kinetic})
    for (double v : *series) EXPECT_TRUE(std::isfinite(v)) << what;
  for (double t : s.temperature) EXPECT_GT(t, 0.0) << what;
  return true;
}

void expect_canonical_kinetic_energy(const Sampler& s, double dof, double temperature,
                                     const std::string& what) {
  if (short_run_checked(s, what)) return;
  const Estimate t = block_estimate(s.temperature);
  const Estimate k = block_variance(s.kinetic);
  const double variance = 0.5 * dof * temperature * temperature;
  std::printf("%s: T = %.4f +- %.4f (bath %.3f); Var K = %.2f +- %.2f (canonical %.2f, dof %g)\n",
              what.c_str(), t.value, t.error, temperature, k.value, k.error, variance, dof);
  EXPECT_NEAR(t.value, temperature, 4.0 * t.error) << what;
  EXPECT_NEAR(k.value, variance, 4.0 * k.error) << what;
  // The checks must be able to tell a count off by the rods or by 3: errors well below that.
  EXPECT_LT(t.error, 0.02 * temperature) << what;
  EXPECT_LT(k.error, 0.1 * variance) << what;
}

std::string thermostat_table(const std::string& type, double damping) {
  return "[thermostat]\ntype = \"" + type +
         "\"\ntemperature = 1.5\ndamping = " + std::to_string(damping) + "\nseed = 2024\n";
}

class Thermostat : public ::testing::TestWithParam<std::string> {};

TEST_P(Thermostat, LjLiquidKineticEnergyIsCanonical) {
  RunInput input = testing::input_from(
      "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.8442\ncells = [3, 3, 3]\n"
      "[velocities]\ntemperature = 1.5\nseed = 7\n[forcefield.pair]\nstyle = \"lj/cut\"\n"
      "cutoff = 2.5\ncoeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
      "[integrator]\ntimestep = 0.004\n[run]\nsteps = 0\n" +
      thermostat_table(GetParam(), 0.1));
  const Sampler s = sample(input, 1000, 60000, 20);
  expect_canonical_kinetic_energy(s, input.degrees_of_freedom.count(), 1.5,
                                  "LJ liquid " + GetParam());
}

// Rigid 4-mers: 3N - rods (Langevin) or 3N - rods - 3 (CSVR) degrees of freedom, of which
// 3 per chain (Langevin) or 3 per chain less 3 (CSVR) are the chains' centres of mass.
TEST_P(Thermostat, RigidChainsKineticEnergyIsCanonicalAndEquipartitioned) {
  RunInput input = testing::input_from(
      "[system]\n[system.chains]\ncount = 30\nlength = 4\ndensity = 0.5\nbond_length = 1.0\n"
      "min_distance = 0.95\nseed = 3\n[velocities]\ntemperature = 1.5\nseed = 11\n"
      "[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n[forcefield.pair]\nstyle = \"wca\"\n"
      "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n[constraints]\n"
      "bonds = \"rigid\"\n[integrator]\ntype = \"gvi\"\ntimestep = 0.004\n[run]\nsteps = 0\n" +
      thermostat_table(GetParam(), 0.1));
  const bool langevin = GetParam() == "langevin";
  const double dof = input.degrees_of_freedom.count();
  EXPECT_EQ(dof, 3 * 120 - 90 - (langevin ? 0 : 3));
  const Sampler s = sample(input, 1000, 60000, 20);
  expect_canonical_kinetic_energy(s, dof, 1.5, "rigid 4-mers " + GetParam());
  if (testing::short_runs()) return;
  const Estimate com = block_estimate(s.centre_of_mass_kinetic);
  const double com_dof = 3 * 30 - (langevin ? 0 : 3);
  std::printf("centres of mass: K = %.3f +- %.3f, equipartition %.3f\n", com.value, com.error,
              0.5 * com_dof * 1.5);
  EXPECT_NEAR(com.value, 0.5 * com_dof * 1.5, 4.0 * com.error);
  EXPECT_LT(com.error, 0.03 * 0.5 * com_dof * 1.5);
  // Energy minus the bath's work is the integrator's own conserved quantity: it moves far
  // less than the energy (a random walk of Verlet's O(h^2) error, 2 % at this strong
  // coupling, 0.1 % at h = 0.002). Bath work that missed the rods' projection of the kicks
  // (a quarter of their energy, 0.3 kT per atom and step here) would drift by thousands.
  const double conserved = standard_deviation(s.conserved), total = standard_deviation(s.total);
  std::printf("standard deviation of E - bath work %.3g, of E %.3g\n", conserved, total);
  EXPECT_LT(conserved, 0.05 * total);
}

TEST_P(Thermostat, HardSphereFluidKineticEnergyIsCanonical) {
  RunInput input = testing::input_from(
      "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.5\ncells = [3, 3, 3]\n"
      "[velocities]\ntemperature = 1.5\nseed = 12\n[forcefield.pair]\nstyle = \"none\"\n"
      "[constraints]\nhard_spheres = { diameter = 1.0 }\n[neighbor]\nskin = 0.4\n"
      "[integrator]\ntype = \"gvi\"\ntimestep = 0.004\n[run]\nsteps = 0\n" +
      thermostat_table(GetParam(), 0.1));
  const Sampler s = sample(input, 1000, 60000, 20);
  expect_canonical_kinetic_energy(s, input.degrees_of_freedom.count(), 1.5,
                                  "hard spheres " + GetParam());
}

INSTANTIATE_TEST_SUITE_P(Both, Thermostat, ::testing::Values("langevin", "csvr"));

// Every integrator takes a thermostat: the mean temperature is the bath's. An LJ liquid
// for the unconstrained integrators, hard spheres for those that reflect (DSI and the
// direct method land contacts inelastically), rigid trimers for DSI and the direct method.
// All periodic: the direct and collision baselines once lost track of the positions that
// a neighbour-list rebuild wraps into the box.
class EveryIntegrator : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(EveryIntegrator, ReachesTheBathTemperature) {
  const auto& [integrator, thermostat] = GetParam();
  std::string system;
  if (integrator == "verlet" || integrator == "midpoint") {
    system =
        "[system.lattice]\ntype = \"fcc\"\ncells = [3, 3, 3]\ndensity = 0.8442\n"
        "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n"
        "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n";
  } else if (integrator == "gvi" || integrator == "collision") {
    system =
        "[system.lattice]\ntype = \"fcc\"\ncells = [3, 3, 3]\ndensity = 0.5\n"
        "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nhard_spheres = { diameter = 1.0 }\n";
  } else {
    system =
        "[system.chains]\ncount = 30\nlength = 3\ndensity = 0.5\nbond_length = 1.0\n"
        "min_distance = 0.95\nseed = 3\n[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n"
        "[forcefield.pair]\nstyle = \"wca\"\ncoeffs = [{ types = [1, 1], epsilon = 1.0, "
        "sigma = 1.0 }]\n[constraints]\nbonds = \"rigid\"\n";
  }
  RunInput input = testing::input_from(
      "[system]\n" + system +
      "[velocities]\ntemperature = 0.5\nseed = 7\n[neighbor]\nskin = 0.4\n" +
      "[integrator]\ntype = \"" + integrator + "\"\ntimestep = 0.004\n[run]\nsteps = 0\n" +
      thermostat_table(thermostat, 0.1));
  // The implicit integrators are slow: fewer, sparser samples.
  const bool implicit = integrator == "midpoint" || integrator == "direct";
  const Sampler s = implicit ? sample(input, 500, 6000, 10) : sample(input, 1000, 20000, 20);
  if (short_run_checked(s, integrator + " + " + thermostat)) return;
  const Estimate t = block_estimate(s.temperature);
  std::printf("%s + %s: T = %.4f +- %.4f (bath 1.5)\n", integrator.c_str(), thermostat.c_str(),
              t.value, t.error);
  EXPECT_NEAR(t.value, 1.5, 4.0 * t.error);
  EXPECT_LT(t.error, 0.03 * 1.5);
}

INSTANTIATE_TEST_SUITE_P(Thermostatted, EveryIntegrator,
                         ::testing::Combine(::testing::Values("verlet", "midpoint", "gvi", "dsi",
                                                              "direct", "collision"),
                                            ::testing::Values("langevin", "csvr")));

}  // namespace
}  // namespace deli
