// The integrator variants against references that do not come from deli's own output:
// GVI without constraints against velocity Verlet (the code's claim), the implicit
// midpoint rule on a harmonic oscillator (analytic), the Discrete-Smooth Integrator on an
// impact (inelastic by construction), and the Moreau reflection on a simultaneous impact
// (analytic).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cli/integrator_factory.hpp"
#include "integrators/gvi.hpp"
#include "integrators/velocity_verlet.hpp"
#include "simulation/thermo.hpp"
#include "support/atoms_input.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

using testing::input_with_atoms;

// A small LJ liquid crossing several neighbour-list rebuilds (periodic: positions are
// wrapped at rebuilds).
std::string lj_liquid(const std::string& integrator) {
  return "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.8442\ncells = [4, 4, 4]\n"
         "[velocities]\ntemperature = 1.44\nseed = 87287\n[forcefield.pair]\nstyle = "
         "\"lj/cut\"\ncutoff = 2.5\ncoeffs = [{types = [1, 1], epsilon = 1.0, sigma = 1.0}]\n"
         "[neighbor]\nskin = 0.3\n[integrator]\ntype = \"" +
         integrator + "\"\ntimestep = 0.005\n[run]\nsteps = 0\n";
}

// GVI with nothing to constrain is velocity Verlet (gvi.hpp): with unit masses the two
// compute the same floating-point operations (p = v, h / m = h), so they agree bit for bit
// until the first neighbour-list rebuild. There they part by rounding, for two reasons:
// GVI rebuilds at the start of the step (its prediction left the list) and wraps the
// positions before the drift, (q + L) + d where Verlet has (q + d) + L (one ulp for an atom
// crossing the box); and the lists, built from different positions, order the pairs
// differently, so the forces are summed in another order. After that the difference is
// rounding amplified by the liquid's chaos: over 2 tau it stays below 1e-10 (as in the
// reversibility test, VelocityVerlet.TimeReversible).
TEST(GviWithoutConstraints, IsVelocityVerletToRounding) {
  RunInput a = testing::input_from(lj_liquid("gvi"));
  RunInput b = testing::input_from(lj_liquid("verlet"));
  ASSERT_TRUE(a.constraints.equalities.empty());
  Gvi gvi(*a.force_field, a.constraints, a.gvi, a.system.particles);
  VelocityVerlet verlet(*b.force_field, b.skin, b.timestep);
  gvi.setup(a.system);
  verlet.setup(b.system);
  int bitwise_steps = 0;
  double worst = 0.0;
  for (int n = 1; n <= 400; ++n) {
    gvi.step(a.system, true);
    verlet.step(b.system, true);
    const bool rebuilt =
        gvi.forces().neighbors().builds() > 1 || verlet.forces().neighbors().builds() > 1;
    const Particles &p = a.system.particles, &q = b.system.particles;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec3 dx = a.system.box.minimum_image(p.position[i] - q.position[i]);
      worst = std::max({worst, norm(dx), norm(p.velocity[i] - q.velocity[i])});
      if (!rebuilt) {
        for (int k = 0; k < 3; ++k) {
          ASSERT_EQ(p.position[i][k], q.position[i][k]) << "step " << n << ", atom " << p.id[i];
          ASSERT_EQ(p.velocity[i][k], q.velocity[i][k]) << "step " << n << ", atom " << p.id[i];
        }
      }
    }
    if (!rebuilt) bitwise_steps = n;
  }
  EXPECT_GE(bitwise_steps, 5) << "steps before the first rebuild";
  EXPECT_GT(verlet.forces().neighbors().builds(), 2) << "the run should cross list rebuilds";
  EXPECT_LT(worst, 1e-10);
  std::printf("bit for bit for %d steps (to the first rebuild), then within %.2e\n", bitwise_steps,
              worst);
}

// The implicit midpoint rule on x'' = -x (V = |x|^2 / 2, unit mass) is the Cayley map of the
// rotation: it keeps the energy exactly and turns phase space by 2 atan(h / 2) per step
// (not h). Reached through `type = "midpoint"` with nothing to constrain.
TEST(MidpointWithoutConstraints, HarmonicOscillatorTurnsByTheCayleyAngle) {
  const double h = 0.1;
  RunInput input = input_with_atoms(
      "midpoint_oscillator", {{{1.0, 0.0, -0.5}, {0.0, 0.5, 0.25}}}, "fff", {-5, -5, -5}, {5, 5, 5},
      "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\n"
      "radial_polynomial = { degree = 1, coefficients = [0.0, 0.5], center = [0, 0, 0] }\n"
      "[integrator]\ntype = \"midpoint\"\ntimestep = 0.1\n[run]\nsteps = 0\n");
  const std::unique_ptr<Integrator> midpoint = make_integrator(input);
  System& s = input.system;
  midpoint->setup(s);
  const Vec3 x0 = s.particles.position[0], v0 = s.particles.velocity[0];
  const double theta = 2.0 * std::atan(h / 2.0);
  const int steps = 1000;
  for (int n = 0; n < steps; ++n) midpoint->step(s, true);
  const double c = std::cos(steps * theta), sn = std::sin(steps * theta);
  const Vec3 x = x0 * c + v0 * sn, v = v0 * c - x0 * sn;
  // The fixed point stops when its change is below the solver tolerance (1e-12); it
  // contracts by about h^2 / 4 per iteration, so each step is exact to far less, and 1000
  // steps of rounding stay below 1e-11.
  EXPECT_LT(norm(s.particles.position[0] - x), 1e-11);
  EXPECT_LT(norm(s.particles.velocity[0] - v), 1e-11);
  // The exact flow turns by h per step: 1000 steps put it 0.083 rad away, far outside.
  const Vec3 exact = x0 * std::cos(steps * h) + v0 * std::sin(steps * h);
  EXPECT_GT(norm(s.particles.position[0] - exact), 1e-2);
  const double e0 = 0.5 * (norm2(x0) + norm2(v0));
  const double e = 0.5 * (norm2(s.particles.position[0]) + norm2(s.particles.velocity[0]));
  // Rounding: a few ulp per step over 1000 steps.
  EXPECT_NEAR(e, e0, 1e-12);
}

// The Discrete-Smooth Integrator puts every active row into the position update's
// complementarity problem and projects the momenta: a ball dropped on a floor lands at
// contact and the projection removes its normal velocity, so it stays on the floor
// (perfectly inelastic), keeping its tangential velocity. GVI bounces the same ball.
TEST(Dsi, BallDropLandsAndStays) {
  const std::string rest =
      "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\ngravity = [0, 0, -9.8]\n"
      "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
      "walls = [{ type = \"plane\", normal = [0, 0, 1] }]\n"
      "[integrator]\ntype = \"dsi\"\ntimestep = 0.01\n[run]\nsteps = 0\n";
  RunInput input = input_with_atoms("dsi_drop", {{{0, 0, 1.5}, {0.3, 0, 0}}}, "fff", {-50, -5, 0},
                                    {50, 5, 10}, rest);
  const std::unique_ptr<Integrator> dsi = make_integrator(input);
  ASSERT_EQ(dsi->name(), "dsi");
  System& s = input.system;
  dsi->setup(s);
  // Free fall from gap 1 takes sqrt(2 / 9.8) = 0.45: 46 steps.
  for (int n = 0; n < 60; ++n) dsi->step(s, true);
  for (int n = 0; n < 500; ++n) {
    dsi->step(s, true);
    ASSERT_NEAR(s.particles.position[0].z, 0.5, 1e-10) << "step " << n;
    ASSERT_NEAR(s.particles.velocity[0].z, 0.0, 1e-10) << "step " << n;
  }
  EXPECT_NEAR(s.particles.velocity[0].x, 0.3, 1e-12);
}

// Moreau's reflection solves one impulse problem over every row of the cluster at once:
// for equal spheres in a line, the first moving at 1 onto two at rest and touching, the
// projection of v = (1, 0, 0) onto the cone of separating velocities (v1 <= v2 <= v3) is
// (1/3, 1/3, 1/3), and its reflection 2 P v - v = (-1/3, 2/3, 2/3): energy and momentum
// kept. The generalized reflection instead resolves the contacts in turn (the first ball
// stops, the last leaves: Gvi.SphereHitsTwoTouchingSpheres).
TEST(MoreauReflection, SimultaneousImpactOfThreeSpheres) {
  RunInput input = input_with_atoms(
      "moreau_three", {{{-3, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {0, 0, 0}}, {{1, 0, 0}, {0, 0, 0}}},
      "fff", {-5, -5, -5}, {5, 5, 5},
      "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nhard_spheres = { diameter = 1.0 }\n"
      "[integrator]\ntype = \"gvi\"\ntimestep = 0.01\n"
      "reflection = { operator = \"moreau\" }\n[run]\nsteps = 0\n");
  const std::unique_ptr<Integrator> gvi = make_integrator(input);
  System& s = input.system;
  gvi->setup(s);
  for (int n = 0; n < 300; ++n) gvi->step(s, true);
  const Particles& p = s.particles;
  EXPECT_NEAR(p.velocity[0].x, -1.0 / 3.0, 1e-14);
  EXPECT_NEAR(p.velocity[1].x, 2.0 / 3.0, 1e-14);
  EXPECT_NEAR(p.velocity[2].x, 2.0 / 3.0, 1e-14);
  for (const Vec3& v : p.velocity) {
    EXPECT_EQ(v.y, 0.0);
    EXPECT_EQ(v.z, 0.0);
  }
}

}  // namespace
}  // namespace deli
