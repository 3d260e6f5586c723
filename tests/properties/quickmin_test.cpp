// quickmin (LAMMPS' min_style quickmin) against analytic minima.
#include "integrators/quickmin.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "support/atoms_input.hpp"

namespace deli {
namespace {

// An LJ dimer started compressed relaxes to the potential's minimum r = 2^(1/6) sigma. The
// stopping rule is |F| < tol on every component; near the minimum F = -k (r - r_min) with
// k = V''(r_min) = 57.15 epsilon / sigma^2, so the distance is within tol / k of it. The
// energy falls to -epsilon, and the velocities are left as they were.
TEST(Quickmin, LjDimerReachesTheAnalyticMinimum) {
  RunInput input = testing::input_with_atoms(
      "quickmin_dimer", {{{0, 0, 0}, {0.1, 0, 0}}, {{1.0, 0.2, 0}, {0, 0, 0}}}, "fff", {-5, -5, -5},
      {5, 5, 5},
      "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 3.0\n"
      "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n[integrator]\ntimestep = "
      "0.005\n[run]\nsteps = 0\n");
  MinimizeSettings settings;
  settings.max_steps = 10000;
  settings.force_tolerance = 1e-6;
  const MinimizeResult result = quickmin(input.system, *input.force_field, input.skin, settings);
  ASSERT_TRUE(result.converged) << result.steps << " steps, largest force " << result.max_force;
  const Particles& p = input.system.particles;
  const double r = norm(p.position[1] - p.position[0]);
  const double r_min = std::pow(2.0, 1.0 / 6.0);
  const double k = 57.146;  // 36 * 2^(2/3) epsilon / sigma^2
  EXPECT_LT(std::abs(r - r_min), 2.0 * settings.force_tolerance / k) << "r = " << r;
  // V(3) = 4 (3^-12 - 3^-6) = -5.5e-3 is the shift of a plain cut at 3: not shifted here.
  EXPECT_NEAR(result.final_energy, -1.0, 1e-9);
  EXPECT_GT(result.initial_energy, result.final_energy);
  EXPECT_LT(result.max_force, settings.force_tolerance);
  EXPECT_EQ(p.velocity[0].x, 0.1);
  EXPECT_EQ(p.velocity[1].x, 0.0);
}

}  // namespace
}  // namespace deli
