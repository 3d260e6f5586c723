// GVI (Verlet) on the behaviours the paper claims and the GVI notes measured: bounces that
// keep their energy, exchanges of velocity, resting and sliding contact, simultaneous
// contacts, conservation of momenta.
#include "integrators/gvi.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "core/error.hpp"
#include "simulation/thermo.hpp"
#include "support/atoms_input.hpp"
#include "support/energy_trend.hpp"
#include "support/process_temp_dir.hpp"
#include "support/short_runs.hpp"
#include "support/statistic.hpp"
#include "support/test_systems.hpp"
#include "support/thread_count.hpp"

namespace deli {
namespace {

using testing::statistic;

using testing::Atom;
using testing::input_with_atoms;

const std::string kNoPairs = "[forcefield.pair]\nstyle = \"none\"\n";
const std::string kGvi = "[integrator]\ntype = \"gvi\"\ntimestep = TIMESTEP\n[run]\nsteps = 0\n";

std::string with_timestep(double h) {
  std::string s = kGvi;
  s.replace(s.find("TIMESTEP"), 8, std::to_string(h));
  return s;
}

struct GviRun {
  RunInput input;
  std::unique_ptr<Gvi> gvi;
  explicit GviRun(RunInput in, ReflectionOperator op = ReflectionOperator::generalized)
      : input(std::move(in)) {
    GviOptions options = input.gvi;
    options.reflection = op;
    gvi = std::make_unique<Gvi>(*input.force_field, input.constraints, options,
                                input.system.particles);
    gvi->setup(input.system);
  }
  System& system() { return input.system; }
  Particles& particles() { return input.system.particles; }
  double energy() { return kinetic_energy(particles()) + gvi->forces().last().potential; }
  void step() { gvi->step(input.system, true); }
};

Vec3 angular_momentum(const Particles& p, const Box& box, Vec3 about = {}) {
  Vec3 l;
  for (std::size_t i = 0; i < p.size(); ++i) {
    l += cross(box.unwrapped(p.position[i], p.image[i]) - about, p.velocity[i] * p.mass[i]);
  }
  return l;
}

// A ball dropped on a floor from height 1 (gap 1): the energy of free flight under a
// constant force is exact in Verlet and the reflection preserves it, so the energy stays
// put to rounding for 1e5 steps, and every apex returns to the start height within the
// O(h) sampling of the parabola.
TEST(Gvi, BallDropKeepsApexAndEnergy) {
  const double h = 0.01;
  GviRun run(input_with_atoms("ball", {{{0, 0, 1.5}, {0, 0, 0}}}, "fff", {-5, -5, 0}, {5, 5, 10},
                              kNoPairs +
                                  "[forcefield.external]\ngravity = [0, 0, -9.8]\n"
                                  "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
                                  "walls = [{ type = \"plane\", normal = [0, 0, 1] }]\n" +
                                  with_timestep(h)));
  const double e0 = run.energy();
  double worst_energy = 0, lowest_apex = 1e9, highest_apex = 0, previous_vz = 0;
  int bounces = 0;
  for (int n = 0; n < 100000; ++n) {
    run.step();
    const Particles& p = run.particles();
    worst_energy = std::max(worst_energy, std::abs(run.energy() - e0));
    if (previous_vz > 0 && p.velocity[0].z <= 0) {
      lowest_apex = std::min(lowest_apex, p.position[0].z);
      highest_apex = std::max(highest_apex, p.position[0].z);
      ++bounces;
    }
    previous_vz = p.velocity[0].z;
    ASSERT_GE(p.position[0].z - 0.5, -1e-10) << "step " << n << ": below the floor";
  }
  EXPECT_GT(bounces, 1000);
  EXPECT_LT(worst_energy, 1e-9 * e0);
  // The apex is sampled at steps: within v h + g h^2 of the true apex, v <= g h there.
  EXPECT_LT(1.5 - lowest_apex, 2 * 9.8 * h * h);
  EXPECT_LT(highest_apex - 1.5, 1e-9);
}

// Equal spheres head on: velocities exchange exactly (one reflection, normal along x).
TEST(Gvi, HeadOnSpheresExchangeVelocities) {
  GviRun run(input_with_atoms(
      "headon", {{{-2, 0, 0}, {1.25, 0, 0}}, {{2, 0, 0}, {-0.5, 0, 0}}}, "fff", {-5, -5, -5},
      {5, 5, 5},
      kNoPairs + "[constraints]\nhard_spheres = { diameter = 1.0 }\n" + with_timestep(0.01)));
  for (int n = 0; n < 400; ++n) run.step();
  const Particles& p = run.particles();
  EXPECT_NEAR(p.velocity[0].x, -0.5, 1e-14);
  EXPECT_NEAR(p.velocity[1].x, 1.25, 1e-14);
  EXPECT_EQ(p.velocity[0].y, 0.0);
  EXPECT_GT(norm(p.position[1] - p.position[0]), 1.0);
}

// A sphere resting on a plane under gravity neither sinks nor bounces over 1e5 steps.
TEST(Gvi, RestingContactStaysAtRest) {
  GviRun run(input_with_atoms("rest", {{{0.3, -0.2, 0.5}, {0, 0, 0}}}, "fff", {-5, -5, 0},
                              {5, 5, 10},
                              kNoPairs +
                                  "[forcefield.external]\ngravity = [0, 0, -9.8]\n"
                                  "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
                                  "walls = [{ type = \"plane\", normal = [0, 0, 1] }]\n" +
                                  with_timestep(0.1)));
  for (int n = 0; n < 100000; ++n) {
    run.step();
    const Particles& p = run.particles();
    ASSERT_NEAR(p.position[0].z, 0.5, 1e-10) << "step " << n;
    ASSERT_NEAR(p.velocity[0].z, 0.0, 1e-10) << "step " << n;
  }
}

// Sliding: a particle moving tangentially along the inside of a spherical wall is held on
// the boundary by the smooth set and keeps its speed and its angular momentum.
TEST(Gvi, SlidesAlongTheInsideOfASphere) {
  const double R = 5.0, r = 0.5;
  GviRun run(input_with_atoms("slide", {{{R - r, 0, 0}, {0, 1.0, 0.3}}}, "fff", {-6, -6, -6},
                              {6, 6, 6},
                              kNoPairs +
                                  "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
                                  "walls = [{ type = \"inside_sphere\", radius = 5.0 }]\n" +
                                  with_timestep(0.05)));
  const Vec3 l0 = angular_momentum(run.particles(), run.system().box);
  const double speed0 = norm(run.particles().velocity[0]);
  for (int n = 0; n < 100000; ++n) {
    run.step();
    const Particles& p = run.particles();
    ASSERT_NEAR(norm(p.position[0]), R - r, 1e-9) << "step " << n << ": left the boundary";
  }
  const Particles& p = run.particles();
  EXPECT_NEAR(norm(p.velocity[0]), speed0, 1e-3 * speed0) << "tangential speed captured";
  EXPECT_LT(norm(angular_momentum(p, run.system().box) - l0), 1e-12 * norm(l0));
}

double kinetic(const Particles& p) {
  return kinetic_energy(p);
}

// A sphere flying into the corner of two perpendicular planes meets both at once: one
// reflection satisfies both jump conditions, and the energy is kept to rounding.
TEST(Gvi, CornerOfTwoPlanes) {
  GviRun run(input_with_atoms("corner", {{{1.5, 1.5, 0}, {-1.0, -1.0, 0.2}}}, "fff", {0, 0, -5},
                              {5, 5, 5},
                              kNoPairs +
                                  "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
                                  "walls = [{ type = \"plane\", normal = [1, 0, 0] },\n"
                                  "         { type = \"plane\", normal = [0, 1, 0] }]\n" +
                                  with_timestep(0.01)));
  const double k0 = kinetic(run.particles());
  for (int n = 0; n < 300; ++n) run.step();
  const Particles& p = run.particles();
  EXPECT_NEAR(p.velocity[0].x, 1.0, 1e-13);
  EXPECT_NEAR(p.velocity[0].y, 1.0, 1e-13);
  EXPECT_NEAR(p.velocity[0].z, 0.2, 1e-13);
  EXPECT_NEAR(kinetic(p), k0, 1e-14 * k0);
}

// A narrow wedge (normals 160 degrees apart): the generalized reflection iterates to a
// state leaving both planes, energy exact; the one-shot Moreau reflection may not.
TEST(Gvi, NarrowWedgeTerminatesAndKeepsEnergy) {
  const double a = 80.0 * M_PI / 180.0;  // each plane tilted 80 degrees from the x axis
  const Vec3 n1{std::sin(a), std::cos(a), 0}, n2{std::sin(a), -std::cos(a), 0};
  char walls[256];
  std::snprintf(walls, sizeof walls,
                "walls = [{ type = \"plane\", normal = [%.17g, %.17g, 0] },\n"
                "         { type = \"plane\", normal = [%.17g, %.17g, 0] }]\n",
                n1.x, n1.y, n2.x, n2.y);
  // Start on the wedge's bisector, inside, moving towards the apex.
  GviRun run(input_with_atoms("wedge", {{{6.0, 0.0, 0}, {-1.0, 0.05, 0}}}, "fff", {-10, -10, -10},
                              {10, 10, 10},
                              kNoPairs + "[constraints]\nhard_spheres = { diameter = 1.0 }\n" +
                                  walls + with_timestep(0.01)));
  const double k0 = kinetic(run.particles());
  for (int n = 0; n < 2000; ++n) run.step();
  const auto stats = run.gvi->take_statistics();
  EXPECT_NEAR(kinetic(run.particles()), k0, 1e-12 * k0);
  EXPECT_EQ(statistic(stats, "stalled_reflections"), 0);
  EXPECT_GT(statistic(stats, "min_gap"), -1e-10);
  EXPECT_TRUE(std::isfinite(statistic(stats, "min_gap"))) << "the walls were never in reach";
  EXPECT_GT(run.particles().velocity[0].x, 0) << "it should leave the wedge";
}

// A sphere in a slit exactly its diameter wide, moving towards one wall: Algorithm 2 sends
// it towards the other wall, then back, and so on for ever (the sign flips are exact, so the
// momenta repeat bit for bit). The loop must notice the cycle, end with no approaching row
// (normal velocity zero, tangential velocity kept), count it, and the sphere must not move
// into either wall.
TEST(Gvi, PinnedSphereReflectionCycleIsDetected) {
  GviRun run(input_with_atoms("pinned", {{{0.5, 0, 0}, {-1.0, 0.3, 0}}}, "fff", {-5, -5, -5},
                              {5, 5, 5},
                              kNoPairs +
                                  "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
                                  "walls = [{ type = \"plane\", normal = [1, 0, 0] },\n"
                                  "         { type = \"plane\", normal = [-1, 0, 0], "
                                  "point = [1, 0, 0] }]\n" +
                                  with_timestep(0.01)));
  for (int n = 0; n < 10; ++n) run.step();
  const Particles& p = run.particles();
  EXPECT_NEAR(p.position[0].x, 0.5, 1e-12);
  EXPECT_NEAR(p.velocity[0].x, 0.0, 1e-12);
  EXPECT_NEAR(p.velocity[0].y, 0.3, 1e-14);
  EXPECT_EQ(statistic(run.gvi->take_statistics(), "cycled_reflections"), 1)
      << "the first step cycles; later ones find nothing approaching";
}

// A sphere hitting two touching spheres in a line: one generalized reflection, momentum
// and energy kept, every pair separating or tangent afterwards.
TEST(Gvi, SphereHitsTwoTouchingSpheres) {
  GviRun run(input_with_atoms(
      "three", {{{-3, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {0, 0, 0}}, {{1, 0, 0}, {0, 0, 0}}}, "fff",
      {-5, -5, -5}, {5, 5, 5},
      kNoPairs + "[constraints]\nhard_spheres = { diameter = 1.0 }\n" + with_timestep(0.01)));
  const double k0 = kinetic(run.particles());
  for (int n = 0; n < 300; ++n) run.step();
  const Particles& p = run.particles();
  Vec3 momentum;
  for (const Vec3& v : p.velocity) momentum += v;
  EXPECT_NEAR(momentum.x, 1.0, 1e-14);
  EXPECT_NEAR(kinetic(p), k0, 1e-14 * k0);
  EXPECT_LE(p.velocity[0].x, p.velocity[1].x + 1e-14);
  EXPECT_LE(p.velocity[1].x, p.velocity[2].x + 1e-14);
}

// The active set holds each row once: the touching pair is active at q (its gap zero) in every
// step's first round, and when the moving sphere hits it, the reflection changes the
// predictions of all three, so the next round looks at the touching pair again; it must find it
// active already. Three spheres in a line have two pairs within contact reach, so no step's
// active set can hold more than two rows.
TEST(Gvi, RowsActiveInTheFirstRoundAreNotJoinedAgain) {
  GviRun run(input_with_atoms(
      "three", {{{-3, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {0, 0, 0}}, {{1, 0, 0}, {0, 0, 0}}}, "fff",
      {-5, -5, -5}, {5, 5, 5},
      kNoPairs + "[constraints]\nhard_spheres = { diameter = 1.0 }\n" + with_timestep(0.01)));
  run.gvi->take_statistics();  // setup's own
  double most = 0.0;
  for (int n = 0; n < 300; ++n) {
    run.step();
    const double active = statistic(run.gvi->take_statistics(), "active_per_step");
    EXPECT_LE(active, 2.0) << "step " << n + 1;
    most = std::max(most, active);
  }
  EXPECT_EQ(most, 2.0) << "the hit's step holds both pairs";
}

// A reflection that sends a sphere beyond its reach. The step's candidate rows are the pairs
// within their two particles' reaches (twice a particle's displacement, at least half the
// largest, Gvi::kReachFloor). A heavy sphere (mass 10, displacement L = v h) hits a light one
// at rest, which leaves at 20/11 of its speed (elastic collision, 1-D) towards a third coming
// at half the heavy one's speed, their gap 2.15 L: beyond the two reaches (L each), inside
// the 2.32 L the two close in the step. The light sphere's new prediction outgrows its reach, so
// the search must collect the rows again and reflect that pair too; missed, the pair overlaps
// at the step's end and the feasibility guard lands it. Elastic reflections keep the energy
// and the momentum, and the three end separating, each slower than the next along the line.
TEST(Gvi, ReflectedSphereBeyondItsReachMeetsTheNextOne) {
  const double h = 0.01, v = 1.0, gap_to_third = 2.15 * v * h;
  GviRun run(input_with_atoms(
      "outgrown",
      {{{-1.0 - 0.5 * v * h, 0, 0}, {v, 0, 0}, 2, 10.0},
       {{0, 0, 0}, {0, 0, 0}, 1, 1.0},
       {{1.0 + gap_to_third, 0, 0}, {-0.5 * v, 0, 0}, 1, 1.0}},
      "fff", {-5, -5, -5}, {5, 5, 5},
      kNoPairs + "[constraints]\nhard_spheres = { diameter = 1.0 }\n" + with_timestep(h)));
  run.gvi->take_statistics();  // setup's own
  const double k0 = kinetic_energy(run.particles());
  run.step();
  const auto first = run.gvi->take_statistics();
  EXPECT_EQ(statistic(first, "landings"), 0) << "the light sphere's second contact was missed";
  EXPECT_EQ(statistic(first, "penetrating_steps"), 0);
  EXPECT_GE(statistic(first, "active_per_step"), 2.0) << "both contacts are in the active set";
  for (int n = 0; n < 100; ++n) run.step();
  const auto later = run.gvi->take_statistics();
  EXPECT_EQ(statistic(later, "landings"), 0);
  EXPECT_GT(statistic(later, "min_gap"), -1e-10);
  const Particles& p = run.particles();
  Vec3 momentum;
  for (std::size_t i = 0; i < p.size(); ++i) momentum += p.velocity[i] * p.mass[i];
  EXPECT_NEAR(momentum.x, 10.0 * v - 0.5 * v, 1e-13);
  EXPECT_NEAR(kinetic_energy(p), k0, 1e-13 * k0);
  EXPECT_LE(p.velocity[0].x, p.velocity[1].x + 1e-14);
  EXPECT_LE(p.velocity[1].x, p.velocity[2].x + 1e-14);
}

// Where no force acts and no row is held (a hard-sphere fluid's usual step), the end positions'
// pass makes the momentum update's velocities too (Gvi::displaced); a force field whose forces
// are zeros it computes (LJ of epsilon 0) leaves them to update_momenta's own pass. The same
// numbers either way: the three spheres above, with one round of the active set so that the
// light sphere's second contact is missed and the feasibility guard lands it (that step's
// velocities come from the landing, not from the pass made before it).
TEST(Gvi, ForcelessStepsVelocitiesAsInTheirOwnPass) {
  const double h = 0.01, v = 1.0, gap_to_third = 2.15 * v * h;
  auto run = [&](const std::string& pairs, double& landings) {
    GviRun gvi(input_with_atoms("forceless",
                                {{{-1.0 - 0.5 * v * h, 0, 0}, {v, 0, 0}, 2, 10.0},
                                 {{0, 0, 0}, {0, 0, 0}, 1, 1.0},
                                 {{1.0 + gap_to_third, 0, 0}, {-0.5 * v, 0, 0}, 1, 1.0}},
                                "fff", {-5, -5, -5}, {5, 5, 5},
                                pairs +
                                    "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
                                    "limits = { active_set_rounds = 1 }\n" +
                                    with_timestep(h)));
    gvi.gvi->take_statistics();  // setup's own
    std::vector<Vec3> states;
    for (int n = 0; n < 40; ++n) {
      gvi.step();
      const Particles& p = gvi.particles();
      states.insert(states.end(), p.position.begin(), p.position.end());
      states.insert(states.end(), p.velocity.begin(), p.velocity.end());
    }
    landings = statistic(gvi.gvi->take_statistics(), "landings");
    return states;
  };
  for (const int threads : {1, 2}) {
    if (threads > 1 && !testing::kThreaded) continue;
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    const testing::ThreadCount count(threads);
    double landed_forceless = 0, landed_zero = 0;
    const std::vector<Vec3> forceless = run(kNoPairs, landed_forceless);
    const std::vector<Vec3> zero_forces =
        run("[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n"
            "coeffs = [{ types = [1, 1], epsilon = 0.0, sigma = 1.0 },\n"
            "          { types = [1, 2], epsilon = 0.0, sigma = 1.0 },\n"
            "          { types = [2, 2], epsilon = 0.0, sigma = 1.0 }]\n",
            landed_zero);
    EXPECT_GE(landed_forceless, 1) << "the missed contact is landed";
    EXPECT_EQ(landed_forceless, landed_zero);
    ASSERT_EQ(forceless.size(), zero_forces.size());
    for (std::size_t k = 0; k < forceless.size(); ++k) {
      const Vec3& a = forceless[k];
      const Vec3& b = zero_forces[k];
      ASSERT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z)
          << "entry " << k << " (step " << k / 6 + 1 << "): " << a.x << " " << a.y << " " << a.z
          << " against " << b.x << " " << b.y << " " << b.z;
    }
  }
}

// The paper's LJ example: six beads joined by rods, hard cores between all pairs not
// joined by a rod, LJ between all pairs, inside a bounding sphere, 1e5 steps.
struct LjChainResult {
  Vec3 l0, l;
  double worst_energy = 0, e0 = 0;
  testing::EnergyTrend trend;
  std::vector<std::pair<std::string, double>> stats;
};

LjChainResult lj_chain_in_sphere(const std::string& feasibility) {
  std::vector<Atom> atoms;
  for (int k = 0; k < 6; ++k) {
    atoms.push_back({{-2.5 + k, 0.3 * (k % 2), 0},
                     {0.3 * std::sin(k), 0.5 * std::cos(3.0 * k), 0.2 * k - 0.5}});
  }
  std::string rods = "rods = [";
  for (int k = 1; k < 6; ++k)
    rods += "{ atoms = [" + std::to_string(k) + ", " + std::to_string(k + 1) + "], length = 1.0 },";
  rods += "]\n";
  GviRun run(
      input_with_atoms("ljchain_" + feasibility, atoms, "fff", {-6, -6, -6}, {6, 6, 6},
                       "[forcefield.special_bonds]\nlj = [1.0, 1.0, 1.0]\n"
                       "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 3.0\n"
                       "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 0.6 }]\n"
                       "[constraints]\n" +
                           rods +
                           "hard_spheres = { diameter = 0.6 }\n"
                           "walls = [{ type = \"inside_sphere\", radius = 5.0 }]\n"
                           "[integrator]\ntype = \"gvi\"\ntimestep = 0.01\nfeasibility = \"" +
                           feasibility + "\"\n[run]\nsteps = 0\n"));
  LjChainResult r;
  r.l0 = angular_momentum(run.particles(), run.system().box);
  r.e0 = run.energy();
  std::vector<double> error;  // every 100 steps
  for (int n = 0; n < 100000; ++n) {
    run.step();
    r.worst_energy = std::max(r.worst_energy, std::abs(run.energy() - r.e0));
    if (n % 100 == 0) error.push_back(run.energy() - r.e0);
  }
  r.stats = run.gvi->take_statistics();
  r.l = angular_momentum(run.particles(), run.system().box);
  r.trend = testing::energy_trend(error);
  std::printf(
      "LJ chain, feasibility %s: max |E - E0| = %.3e (E0 = %.4f), |dL| = %.3e, trend "
      "%.3e, fluctuation %.3e\n",
      feasibility.c_str(), r.worst_energy, r.e0, norm(r.l - r.l0), r.trend.trend,
      r.trend.fluctuation);
  return r;
}

// With the default guard: angular momentum about the centre kept to 1e-12 relative (rotation
// invariance), rods to 1e-10 relative at every step, no overlap.
TEST(Gvi, LjChainInSphereKeepsAngularMomentumAndRods) {
  const LjChainResult r = lj_chain_in_sphere("restore");
  EXPECT_LT(statistic(r.stats, "max_rod_violation"), 1e-10);
  EXPECT_GT(statistic(r.stats, "min_gap"), -1e-10) << "overlap";
  EXPECT_TRUE(std::isfinite(statistic(r.stats, "min_gap"))) << "no contact was ever in reach";
  EXPECT_LT(norm(r.l - r.l0), 1e-12 * std::max(1.0, norm(r.l0)));
}

// The literal Algorithm 1 (feasibility = "none") keeps angular momentum about the centre
// (rotation invariance) and lets steps end overlapped here (about 100 of 1e5, to -1.8e-3):
// that is what the feasibility guard is for.
TEST(Gvi, LjChainInSphereLiteralAlgorithmKeepsAngularMomentumButOverlaps) {
  const LjChainResult r = lj_chain_in_sphere("none");
  EXPECT_GT(statistic(r.stats, "penetrating_steps"), 0) << "expected the literal algorithm "
                                                           "to end some steps overlapped";
  EXPECT_LT(norm(r.l - r.l0), 1e-12 * std::max(1.0, norm(r.l0)));
}

// KNOWN FAILURE (issue 17): the paper's claim for its algorithm, a bounded energy error, is
// not borne out here. Over 1e5 steps the trend-to-fluctuation ratio depends on rounding
// (0.15 on one build, 0.82 on the next, whose contact solves differ in the last bits);
// over 1e6 steps the largest error grows from 0.13 to 0.52 (|E0| = 0.28), about as
// t^0.6: a random walk rather than a bounded oscillation (the guarded runs below grow
// linearly). Disabled until understood; run it with --gtest_also_run_disabled_tests.
TEST(Gvi, DISABLED_LjChainInSphereLiteralAlgorithmKeepsEnergyBounded) {
  const LjChainResult r = lj_chain_in_sphere("none");
  EXPECT_LT(r.trend.ratio(), 0.5);
}

// KNOWN FAILURE (issue 17, found by asserting this test's energy instead of printing it):
// with a feasibility guard the energy drifts, because every landing changes it: 1e5 steps
// give -1.2 (restore, 137 landings, no deficit reported), +5.6 (reflect), +11 (inelastic)
// against |E0| = 0.28 (1e6 steps: restore -7.5), against 0.13 for the literal algorithm
// (0.52 at 1e6 steps). Here the hard core equals the LJ sigma, so a landing moves a bead
// on the steep wall of the potential.
// Disabled until the guard is fixed; run it with --gtest_also_run_disabled_tests.
TEST(Gvi, DISABLED_LjChainInSphereRestoreGuardKeepsEnergyBounded) {
  const LjChainResult r = lj_chain_in_sphere("restore");
  EXPECT_LT(r.trend.ratio(), 0.5);
}

// The forces at a step's end are evaluated with a neighbour list valid at its end positions x.
// A dumbbell (rod 1, h 0.05) translating at u = 1 and spinning at v = 1 per bead: bead 1's
// free step (u, v) h moves it 0.0707 from where the list was built, the rod pulls it to
// 0.0725 (x = (0.5 (sqrt(1 - (2hv)^2) - 1) - hu, hv) from its start). With the skin 0.143
// (half of it: 0.0715) the step's prediction leaves the list valid and x does not: the
// force evaluation at x must rebuild it.
TEST(Gvi, ForcesAtTheStepsEndUseAListValidAtItsPositions) {
  const double u = 1.0, v = 1.0;
  // One thread: the end positions in a pass of their own; two: made with the rods' solves
  // (Gvi::steps_by_cluster). Each tests the list at x as it makes it.
  for (const int threads : {1, 2}) {
    if (threads > 1 && !testing::kThreaded) continue;
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    const testing::ThreadCount count(threads);
    GviRun run(input_with_atoms("spinning_dumbbell",
                                {{{5.5, 5, 5}, {-u, v, 0}}, {{4.5, 5, 5}, {-u, -v, 0}}}, "ppp",
                                {0, 0, 0}, {10, 10, 10},
                                "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n"
                                "coeffs = [{ types = [1, 1], epsilon = 0.0, sigma = 1.0 }]\n"
                                "[neighbor]\nskin = 0.143\n"
                                "[constraints]\nrods = [{ atoms = [1, 2], length = 1.0 }]\n"
                                "[integrator]\ntype = \"gvi\"\nlagrangian = \"verlet\"\n"
                                "timestep = 0.05\n[run]\nsteps = 0\n"));
    const NeighborList& list = run.gvi->forces().neighbors();
    const Vec3 start = run.particles().position[0];
    const std::int64_t builds = list.builds();
    run.step();
    const double moved = norm(run.particles().position[0] - start);
    ASSERT_NEAR(moved, 0.0725045, 1e-6);  // the analytic x above
    EXPECT_GT(moved, 0.143 / 2);
    EXPECT_FALSE(list.needs_rebuild(run.particles().position));
    EXPECT_EQ(list.builds(), builds + 1);
  }
}

// And only there, when nothing in the step reads the list before the forces at x (rods alone).
// A dumbbell at rest (rod 1) whose beads repel each other (LJ, sigma 1.1, no exclusions):
// F = 24 (2 1.1^12 - 1.1^6) = 108.1 along the rod, so each bead's free step h^2 F / (2 m) =
// 0.135 leaves the list (half the skin: 0.0715) while the rod holds x at the start. No
// rebuild, and the forces at x are those of a fresh list. (Tested on the free prediction, the
// step was refused: "a particle would move more than half the neighbour skin".)
TEST(Gvi, RodsAloneKeepTheListWhereOnlyTheFreeStepLeavesIt) {
  for (const int threads : {1, 2}) {
    if (threads > 1 && !testing::kThreaded) continue;
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    const testing::ThreadCount count(threads);
    GviRun run(input_with_atoms("repelling_dumbbell", {{{5.5, 5, 5}, {}}, {{4.5, 5, 5}, {}}}, "ppp",
                                {0, 0, 0}, {10, 10, 10},
                                "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n"
                                "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.1 }]\n"
                                "[neighbor]\nskin = 0.143\n"
                                "[constraints]\nrods = [{ atoms = [1, 2], length = 1.0 }]\n"
                                "[integrator]\ntype = \"gvi\"\nlagrangian = \"verlet\"\n"
                                "timestep = 0.05\n[run]\nsteps = 0\n"));
    const NeighborList& list = run.gvi->forces().neighbors();
    const double h = 0.05, f = 24.0 * (2.0 * std::pow(1.1, 12) - std::pow(1.1, 6));
    ASSERT_NEAR(run.gvi->forces().force()[0].x, f, 1e-9 * f);  // the pair is not excluded
    ASSERT_GT(0.5 * h * h * f, 0.143 / 2);
    const Vec3 start = run.particles().position[0];
    const std::int64_t builds = list.builds();
    run.step();
    EXPECT_LT(norm(run.particles().position[0] - start), 1e-12);
    EXPECT_EQ(list.builds(), builds);
    const testing::Evaluated fresh = testing::evaluate(run.input);
    EXPECT_EQ(run.gvi->forces().force()[0].x, fresh.force[0].x);
  }
}

// Where the contact rows' search reads the prediction: a sphere whose free step (h v = 0.3)
// is more than half the skin (0.15) leaves the list built at its start position too, and
// the step is refused, naming the step and the remedy; at h v = 0.1 every step's prediction
// is covered, by the list as it was or by one built at the step's start (the test made in
// the prediction's pass after a build).
TEST(Gvi, ASphereLeavingTheNewListInOneStepStopsTheRun) {
  for (const int threads : {1, 2}) {
    if (threads > 1 && !testing::kThreaded) continue;
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    const testing::ThreadCount count(threads);
    auto fluid = [](double speed) {
      std::vector<Atom> atoms;
      for (int k = 0; k < 1200; ++k) {
        atoms.push_back({{0.5 + 2.0 * (k % 10), 0.5 + 2.0 * ((k / 10) % 10), 0.5 + 2.0 * (k / 100)},
                         {k == 7 ? speed : 0.0, 0, 0}});
      }
      return input_with_atoms("fast_sphere", atoms, "ppp", {0, 0, 0}, {20, 20, 24},
                              kNoPairs + "[constraints]\nhard_spheres = { diameter = 1.0 }\n" +
                                  "[neighbor]\nskin = 0.3\n" + with_timestep(0.01));
    };
    GviRun slow(fluid(10.0));
    const NeighborList& list = slow.gvi->forces().neighbors();
    const std::int64_t builds = list.builds();
    for (int n = 0; n < 6; ++n) slow.step();
    EXPECT_GE(list.builds(), builds + 2);
    EXPECT_NEAR(slow.particles().position[7].x, 14.5 + 0.6, 1e-12);
    GviRun fast(fluid(30.0));
    try {
      fast.step();
      ADD_FAILURE() << "a step of 0.3 with a skin of 0.3 was taken";
    } catch (const SimulationError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("step 1: a particle would move more than half the neighbour skin"),
                std::string::npos)
          << message;
      EXPECT_NE(message.find("increase [neighbor] skin"), std::string::npos) << message;
    }
  }
}
// Pair contacts exchange momentum only: a hard-sphere gas in a periodic box keeps its total
// momentum to rounding.
TEST(Gvi, HardSphereGasKeepsLinearMomentum) {
  RunInput input = parse_run_input(
      "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.5\ncells = [4, 4, 4]\n"
      "[velocities]\ntemperature = 1.0\nseed = 3\n[forcefield.pair]\nstyle = \"none\"\n"
      "[constraints]\nhard_spheres = { diameter = 1.0 }\n[neighbor]\nskin = 0.5\n" +
          with_timestep(0.005),
      deli::testing::process_temp_dir() + "/gas.toml");
  // A small drift to see it preserved, not just zero.
  for (Vec3& v : input.system.particles.velocity) v += Vec3{0.1, -0.05, 0.02};
  GviRun run(std::move(input));
  const Vec3 m0 = total_momentum(run.particles());
  const double k0 = kinetic(run.particles());
  for (int n = 0; n < 4000; ++n) run.step();
  const auto stats = run.gvi->take_statistics();
  const double reflected = statistic(stats, "reflected");
  EXPECT_GT(statistic(stats, "min_gap"), -1e-10);
  EXPECT_TRUE(std::isfinite(statistic(stats, "min_gap")));
  EXPECT_GT(reflected, 100) << "the gas should collide";
  EXPECT_LT(norm(total_momentum(run.particles()) - m0),
            1e-12 * static_cast<double>(run.particles().size()));
  EXPECT_NEAR(kinetic(run.particles()), k0, 1e-10 * k0);
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// The notes' slow landing: a ball released at rest 0.02 above a floor with h = 0.1, less
// than g h^2 / 2: the predictor is below the floor but nothing approaches, so the literal
// algorithm ends steps overlapped (and cycles through the floor). The default guard
// ("restore") lands it at contact, bounces it and gives back the energy of the start of the
// step: no overlap, energy exact, for 1e5 steps.
double slow_landing(Feasibility guard, double& min_gap) {
  RunInput input = testing::input_with_atoms(
      "slow", {{{0, 0, 0.52}, {0, 0, 0}}}, "fff", {-5, -5, 0}, {5, 5, 10},
      "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\ngravity = [0, 0, -9.8]\n"
      "[constraints]\nhard_spheres = { diameter = 1.0 }\n"
      "walls = [{ type = \"plane\", normal = [0, 0, 1] }]\n"
      "[integrator]\ntype = \"gvi\"\ntimestep = 0.1\n[run]\nsteps = 0\n");
  GviOptions options = input.gvi;
  options.feasibility = guard;
  Gvi gvi(*input.force_field, input.constraints, options, input.system.particles);
  System& s = input.system;
  gvi.setup(s);
  const double e0 = kinetic_energy(s.particles) + gvi.forces().last().potential;
  double worst = 0;
  min_gap = 1e9;
  for (int n = 0; n < 100000; ++n) {
    gvi.step(s, true);
    worst =
        std::max(worst, std::abs(kinetic_energy(s.particles) + gvi.forces().last().potential - e0));
    min_gap = std::min(min_gap, s.particles.position[0].z - 0.5);
  }
  return worst;
}

TEST(GviFeasibility, SlowLandingRestoreKeepsEnergyWithoutOverlap) {
  double gap = 0;
  const double error = slow_landing(Feasibility::restore, gap);
  EXPECT_GT(gap, -1e-10);
  EXPECT_LT(error, 1e-12);
}

TEST(GviFeasibility, SlowLandingLiteralAlgorithmOverlaps) {
  double gap = 0;
  slow_landing(Feasibility::none, gap);
  EXPECT_LT(gap, -0.02) << "the literal algorithm is expected to end steps below the floor";
}

// "reflect" lands the ball at contact and reflects what still approaches, elastically,
// but does not give back the potential energy the landing changed: m g times the lift, the
// lift at most g h^2 / 2, so at most 0.48 here. No overlap, and the energy error stays
// within one landing's worth over 1e5 steps (measured 4.2e-2: no accumulation).
TEST(GviFeasibility, SlowLandingReflectBouncesWithoutOverlap) {
  double gap = 0;
  const double error = slow_landing(Feasibility::reflect, gap);
  std::printf("slow landing, reflect: energy error %.3e\n", error);
  EXPECT_GT(gap, -1e-10);
  EXPECT_GT(error, 1e-12) << "reflect is not expected to restore the energy exactly";
  EXPECT_LT(error, 9.8 * 9.8 * 0.1 * 0.1 / 2);
}

TEST(GviFeasibility, SlowLandingInelasticLosesEnergy) {
  double gap = 0;
  const double error = slow_landing(Feasibility::inelastic, gap);
  EXPECT_GT(gap, -1e-10);
  EXPECT_GT(error, 0.1);
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

struct PogoResult {
  double max_relative_energy_error = 0, final_relative_energy_error = 0, min_gap = 1e9;
};

// The paper's pogo stick (q1 = 6, q2 = 1, at rest; k = 10, l = 5, g = 9.8, h = 0.1) with
// shadow-Hamiltonian reflections, to t = 1e4.
PogoResult pogo(Feasibility guard) {
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/paper/pogo_stick.toml");
  GviOptions options = input.gvi;
  options.energy = ReflectionEnergy::shadow;
  options.feasibility = guard;
  Gvi gvi(*input.force_field, input.constraints, options, input.system.particles);
  System& s = input.system;
  gvi.setup(s);
  const double e0 = kinetic_energy(s.particles) + gvi.forces().last().potential;
  PogoResult r;
  double e = e0;
  for (int n = 0; n < testing::steps_or_prefix(100000, 10000); ++n) {
    gvi.step(s, true);
    e = kinetic_energy(s.particles) + gvi.forces().last().potential;
    r.max_relative_energy_error = std::max(r.max_relative_energy_error, std::abs(e - e0) / e0);
    r.min_gap = std::min(r.min_gap, s.particles.position[1].z);
  }
  r.final_relative_energy_error = (e - e0) / e0;
  return r;
}

// The notes measured, with the literal algorithm, 19 steps in 1e5 ending below the ground
// (to -0.043), and a 7.6 % energy loss with inelastic landings. The default guard keeps the
// bottom mass above ground and the energy in the literal algorithm's band (1.4e-2).
TEST(GviFeasibility, PogoStickShadowReflections) {
  const PogoResult literal = pogo(Feasibility::none);
  const PogoResult inelastic = pogo(Feasibility::inelastic);
  const PogoResult restore = pogo(Feasibility::restore);
  std::printf("pogo, shadow-H: none %.3e (gap %.3f), inelastic %.3e (final %.3e), restore %.3e\n",
              literal.max_relative_energy_error, literal.min_gap,
              inelastic.max_relative_energy_error, inelastic.final_relative_energy_error,
              restore.max_relative_energy_error);
  EXPECT_GT(restore.min_gap, -1e-10);
  EXPECT_LT(restore.max_relative_energy_error, 1.5e-2);
  // Under the sanitizers (support/short_runs.hpp) the first 1e4 steps, over which the two
  // bounds above hold as over the whole run; what the literal and inelastic runs reach by
  // the end is the plain pass's.
  if (testing::short_runs()) return;
  EXPECT_LT(literal.min_gap, -0.04);
  EXPECT_LT(inelastic.final_relative_energy_error, -0.05);
  EXPECT_LT(std::abs(restore.final_relative_energy_error), 1e-2);
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// A position update that cannot converge (two rods on one pair, of lengths 1 and 1.5)
// stops the run with the step, the cluster and the residual, and leaves the problem in a
// file.
TEST(GviFailure, UnconvergedSolveIsReportedWithItsProblem) {
  RunInput input = testing::input_with_atoms(
      "fail", {{{0, 0, 0}, {0.3, 0.1, 0}}, {{1, 0, 0}, {-0.2, 0.4, 0.1}}}, "fff", {-5, -5, -5},
      {5, 5, 5},
      "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nrods = [{ atoms = [1, 2], length = "
      "1.0 }]\n[integrator]\ntype = \"gvi\"\ntimestep = 0.01\n[run]\nsteps = 0\n");
  // A second rod on the same pair with another length: the input refuses it (issue 14), so
  // it is added behind the reader's back to reach the solver's failure report.
  Constraint conflicting = input.constraints.equalities.front();
  conflicting.length = 1.5;
  input.constraints.equalities.push_back(conflicting);
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  try {
    gvi.setup(input.system);
    gvi.step(input.system, true);
    FAIL() << "expected a solver failure";
  } catch (const SimulationError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("did not converge"), std::string::npos) << what;
    EXPECT_NE(what.find("from atom 1"), std::string::npos) << what;
    EXPECT_NE(what.find("residual"), std::string::npos) << what;
    // It fails putting the start on the rods: the message says so, not "reduce the timestep".
    EXPECT_NE(what.find("cannot all hold from the starting configuration"), std::string::npos)
        << what;
    const auto at = what.find("deli-failed-solve-step");
    ASSERT_NE(at, std::string::npos) << what;
    const std::string file = what.substr(at, what.find(';', at) - at);
    std::ifstream dumped(file);
    EXPECT_TRUE(dumped.good()) << file;
    std::string header;
    std::getline(dumped, header);
    EXPECT_NE(header.find("failed position update"), std::string::npos);
    std::remove(file.c_str());
  }
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// Same input, same result, bit for bit: the default slit melt (rods, contacts, walls).
TEST(Gvi, DeterministicOnTheDefaultInput) {
  auto run_once = [] {
    RunInput input =
        load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/rigid_slit.toml");
    Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
    gvi.setup(input.system);
    for (int n = 0; n < 150; ++n) gvi.step(input.system, n % 50 == 0);
    return input.system.particles;
  };
  const Particles a = run_once(), b = run_once();
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(a.position[i][k], b.position[i][k]) << "atom " << a.id[i];
      ASSERT_EQ(a.velocity[i][k], b.velocity[i][k]) << "atom " << a.id[i];
    }
  }
}

}  // namespace
}  // namespace deli
