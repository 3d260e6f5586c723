// The baselines (direct method, collision integrator) in a periodic box: a hard-sphere gas
// whose atoms cross the boundaries and whose neighbour list is rebuilt (and positions
// wrapped) during the run. Whatever a method's treatment of impacts, momentum is exchanged
// in pairs (total kept to rounding), no pair ends a step overlapped, and no atom jumps: a
// prediction taken before a rebuild wraps the positions would move an atom by a box length.
#include <gtest/gtest.h>

#include <cmath>

#include "cli/integrator_factory.hpp"
#include "input/run_input.hpp"
#include "simulation/thermo.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

std::string gas(const std::string& integrator) {
  return "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.5\ncells = [3, 3, 3]\n"
         "[velocities]\ntemperature = 1.0\nseed = 3\n[forcefield.pair]\nstyle = \"none\"\n"
         "[constraints]\nhard_spheres = { diameter = 1.0 }\n[neighbor]\nskin = 0.5\n"
         // Atoms are followed by index from step to step: not sorted in space.
         "sort_every = 0\n"
         "[integrator]\n" +
         integrator + "\ntimestep = 0.005\n[run]\nsteps = 0\n";
}

struct GasRun {
  double largest_jump = 0, worst_overlap = 0, momentum_change = 0, kinetic_change = 0;
  std::int64_t builds = 0;
};

GasRun run_gas(const std::string& integrator) {
  RunInput input = testing::input_from(gas(integrator));
  for (Vec3& v : input.system.particles.velocity) v += Vec3{0.1, -0.05, 0.02};
  std::unique_ptr<Integrator> method = make_integrator(input);
  System& s = input.system;
  method->setup(s);
  const Vec3 m0 = total_momentum(s.particles);
  const double k0 = kinetic_energy(s.particles);
  GasRun r;
  const std::size_t n = s.particles.size();
  for (int step = 0; step < 2000; ++step) {
    std::vector<Vec3> before(n);
    for (std::size_t i = 0; i < n; ++i) {
      before[i] = s.box.unwrapped(s.particles.position[i], s.particles.image[i]);
    }
    method->step(s, true);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 after = s.box.unwrapped(s.particles.position[i], s.particles.image[i]);
      r.largest_jump = std::max(r.largest_jump, norm(after - before[i]));
      for (std::size_t j = i + 1; j < n; ++j) {
        const double gap =
            norm(s.box.minimum_image(s.particles.position[i] - s.particles.position[j])) - 1.0;
        r.worst_overlap = std::max(r.worst_overlap, -gap);
      }
    }
  }
  r.momentum_change = norm(total_momentum(s.particles) - m0);
  r.kinetic_change = (kinetic_energy(s.particles) - k0) / k0;
  r.builds = method->forces().neighbors().builds();
  return r;
}

void expect_sane(const GasRun& r, const std::string& what) {
  std::printf("%s: largest step %.3e, overlap %.3e, |dP| %.3e, dK/K %.3e, %lld list builds\n",
              what.c_str(), r.largest_jump, r.worst_overlap, r.momentum_change, r.kinetic_change,
              static_cast<long long>(r.builds));
  EXPECT_GT(r.builds, 2) << what << ": the run should cross list rebuilds";
  // Speeds stay below 6 here (T = 1, 108 atoms): a step moves an atom at most 0.03.
  EXPECT_LT(r.largest_jump, 0.05) << what;
  EXPECT_LT(r.worst_overlap, 1e-10) << what;
  EXPECT_LT(r.momentum_change, 1e-12 * 108) << what;
}

TEST(PeriodicBaselines, CollisionIntegratorHardSphereGas) {
  const GasRun r = run_gas("type = \"collision\"");
  expect_sane(r, "collision");
  // Elastic impacts with no potential: the kinetic energy is kept to rounding.
  EXPECT_LT(std::abs(r.kinetic_change), 1e-10);
}

TEST(PeriodicBaselines, DirectEndpointHardSphereGas) {
  expect_sane(run_gas("type = \"direct\""), "direct");
}

}  // namespace
}  // namespace deli
