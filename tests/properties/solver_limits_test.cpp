// GVI through solves that were ill-posed or capped: a rigid rod loop with a redundant rod
// (a triangular bipyramid held by all ten distances) tumbling onto a floor, which before the
// position update's least-norm fallback for nearly singular Newton matrices stopped at its
// first step; and iteration limits set too small, whose hits are counted or stop the run with a
// problem file that `solve-problem` solves again. Expected values: conservation laws (the
// floor and gravity act along z, the rods internally), the constraints themselves, and the
// limits' documented behaviour (README, "Solver limits").
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cli/integrator_factory.hpp"
#include "core/error.hpp"
#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "simulation/thermo.hpp"
#include "solvers/position_problem.hpp"
#include "support/atoms_input.hpp"
#include "support/scratch_files.hpp"
#include "support/statistic.hpp"

namespace deli {
namespace {

using testing::statistic;

// The rigid loop of tests/solver_problems/rigid_bipyramid_redundant_rod.txt: a triangular
// bipyramid (unit masses) held by all ten of its distances, nine independent rods and a
// redundant one, 0.5 above a floor under gravity, with velocities that setup makes rigid.
RunInput bipyramid(const std::string& name, const std::string& limits) {
  const double s3 = std::sqrt(3.0);
  const std::vector<Vec3> x{
      {1, 0, 1.5}, {-0.5, s3 / 2, 1.5}, {-0.5, -s3 / 2, 1.5}, {0, 0, 2.5}, {0, 0, 0.5}};
  const std::vector<Vec3> v{
      {0.3, -1.0, 0.2}, {1.1, 0.4, -0.7}, {-0.5, 0.9, 0.3}, {0.2, 0.2, 1.0}, {-0.4, 0.1, 0.5}};
  std::vector<testing::Atom> atoms;
  for (std::size_t k = 0; k < x.size(); ++k) atoms.push_back({x[k], v[k]});
  std::string rods = "rods = [";
  const std::pair<int, int> pairs[] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 1},
                                       {3, 2}, {4, 0}, {4, 1}, {4, 2}, {3, 4}};
  for (const auto& [i, j] : pairs) {
    char rod[120];
    std::snprintf(rod, sizeof rod, "%s{ atoms = [%d, %d], length = %.17g }",
                  rods.size() > 8 ? ", " : "", i + 1, j + 1, norm(x[i] - x[j]));
    rods += rod;
  }
  rods += "]\n";
  return testing::input_with_atoms(
      name, atoms, "fff", {-10, -10, -10}, {10, 10, 10},
      "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\ngravity = [0, 0, -9.8]\n"
      "[constraints]\n" +
          rods + "walls = [{ type = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }]\n" +
          limits + "[integrator]\ntype = \"gvi\"\ntimestep = 0.005\n[run]\nsteps = 0\n");
}

// Through 4000 steps (t = 20, impacts of its corners on the floor): every rod held to 1e-10
// of its length, no corner below the floor beyond the gap tolerance, and P_x, P_y and L_z
// (about the vertical axis through the origin) as at the start: the floor's and gravity's
// forces are vertical and the rods' impulses internal and central.
TEST(RigidRodLoop, TumblesOntoAFloorWithEveryRodHeld) {
  RunInput input = bipyramid("RigidRodLoop" + std::to_string(::getpid()), "");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  gvi.setup(input.system);
  const Particles& P = input.system.particles;
  auto momentum = [&] {
    Vec3 p{}, l{};
    for (std::size_t i = 0; i < P.size(); ++i) {
      p += P.velocity[i] * P.mass[i];
      l += cross(P.position[i], P.velocity[i] * P.mass[i]);
    }
    return std::pair{p, l.z};
  };
  const auto [p0, lz0] = momentum();
  for (int step = 0; step < 4000; ++step) gvi.step(input.system, true);
  const auto stats = gvi.take_statistics();
  EXPECT_LT(statistic(stats, "max_rod_violation"), 1e-10);
  EXPECT_GT(statistic(stats, "min_gap"), -1e-10);
  EXPECT_GT(statistic(stats, "reflected"), 0) << "no impact on the floor: the test tests nothing";
  const auto [p1, lz1] = momentum();
  EXPECT_NEAR(p1.x, p0.x, 1e-11);
  EXPECT_NEAR(p1.y, p0.y, 1e-11);
  EXPECT_NEAR(lz1, lz0, 1e-11);
  for (const char* cap : {"active_set_caps", "feasibility_caps", "qp_caps"}) {
    EXPECT_EQ(statistic(stats, cap), 0) << cap;
  }
}

// A Newton limit too small for the first step stops the run naming the step, the cluster,
// the residual and the limit, and leaves the problem in a file; read back, it is the failed
// problem (same residual after the same iterations) and the default limit solves it.
TEST(SolverLimits, NewtonLimitHitStopsWithTheProblemToSolveAgain) {
  RunInput input =
      bipyramid("NewtonLimit" + std::to_string(::getpid()), "limits = { newton = 1 }\n");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  gvi.setup(input.system);  // the start is on the rods: setup needs no iteration
  // The problem file goes to the working directory, where other tests' failures write
  // theirs under the same name: work in a directory of this test's own.
  const testing::ScratchDirectory own("NewtonLimit");
  try {
    gvi.step(input.system, true);
    FAIL() << "expected the Newton limit to stop the run";
  } catch (const SimulationError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("step 1:"), std::string::npos) << what;
    EXPECT_NE(what.find("cluster of 5 atoms from atom 1"), std::string::npos) << what;
    EXPECT_NE(what.find("after 1 Newton iterations"), std::string::npos) << what;
    EXPECT_NE(what.find("newton = 1"), std::string::npos) << what;
    ASSERT_NE(what.find("is in deli-failed-solve-step1.txt"), std::string::npos) << what;
    const PositionProblem problem = read_position_problem("deli-failed-solve-step1.txt");
    EXPECT_EQ(problem.newton_limit, 1);
    const PositionUpdate again = solve_position_problem(problem);
    EXPECT_FALSE(again.status.converged);
    EXPECT_EQ(again.status.residual, problem.failed_residual);
    const PositionUpdate solved = solve_position_problem(problem, SolverLimits{}.newton);
    EXPECT_TRUE(solved.status.converged) << describe_position_solve(problem, solved);
  }
}

// An active-set limit of one round: a particle sent into a wall, reflected, then predicted
// into a second wall needs two rounds; with one the step goes on with the rows found and
// the hit is counted in `active_set_caps`; the feasibility guard lands the missed wall, so
// the step ends without overlap. Two parallel walls 0.03 apart, a point particle at 0.01
// from the lower one moving down fast (reflected up, the prediction crosses the upper).
TEST(SolverLimits, ActiveSetLimitHitIsCountedAndTheStepStaysFeasible) {
  const std::string walls =
      "walls = [{ type = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] },"
      " { type = \"plane\", point = [0, 0, 0.03], normal = [0, 0, -1] }]\n";
  RunInput input = testing::input_with_atoms(
      "ActiveSetLimit" + std::to_string(::getpid()), {{{0, 0, 0.01}, {0, 0, -5.0}}}, "fff",
      {-10, -10, -10}, {10, 10, 10},
      "[forcefield.pair]\nstyle = \"none\"\n[constraints]\n" + walls +
          "limits = { active_set_rounds = 1 }\n[integrator]\ntype = \"gvi\"\ntimestep = "
          "0.01\n[run]\nsteps = 0\n");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  gvi.setup(input.system);
  gvi.step(input.system, true);
  const auto stats = gvi.take_statistics();
  EXPECT_EQ(statistic(stats, "active_set_caps"), 1);
  EXPECT_GT(statistic(stats, "min_gap"), -1e-10);
  const double z = input.system.particles.position[0].z;
  EXPECT_GE(z, -1e-10);
  EXPECT_LE(z, 0.03 + 1e-10);
}

// The reflection QP's limit: a point particle driven into a corner (floor and side wall,
// both 0.01 away, velocity (-5, 0, -5), h = 0.01) needs a two-row QP. Lawson-Hanson enters one
// row per iteration and confirms in one more, so qp_iterations = 1 stops every such solve
// unfinished: each is counted in qp_caps, the reflection is handled as a stall (inelastic
// projection) and the feasibility guard keeps the step clear of both walls. With the default limit
// (10 n + 10) nothing is counted and the bounce is elastic: orthogonal normals reverse each normal
// component, v = (5, 0, 5) (analytic).
TEST(SolverLimits, QpLimitHitIsCountedAsAStall) {
  auto corner_step = [](const std::string& limits) {
    RunInput input = testing::input_with_atoms(
        "QpLimit" + std::to_string(::getpid()), {{{0.01, 0, 0.01}, {-5.0, 0, -5.0}}}, "fff",
        {-10, -10, -10}, {10, 10, 10},
        "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nwalls = [{ type = \"plane\", "
        "point = [0, 0, 0], normal = [0, 0, 1] }, { type = \"plane\", point = [0, 0, 0], "
        "normal = [1, 0, 0] }]\n" +
            limits + "[integrator]\ntype = \"gvi\"\ntimestep = 0.01\n[run]\nsteps = 0\n");
    Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
    gvi.setup(input.system);
    gvi.step(input.system, true);
    return std::pair{gvi.take_statistics(), input.system.particles.velocity[0]};
  };
  const auto [capped, v_capped] = corner_step("limits = { qp_iterations = 1 }\n");
  EXPECT_GE(statistic(capped, "qp_caps"), 1);
  EXPECT_GE(statistic(capped, "stalled_reflections"), 1);
  EXPECT_GT(statistic(capped, "min_gap"), -1e-10);
  // Not the elastic corner bounce: the stall's inelastic projection stops the row it
  // entered, then the default feasibility guard (restore) gives the start's energy back along
  // the normals (measured here: v = (7.07, 0, 0)).
  EXPECT_GT(norm(v_capped - Vec3{5.0, 0, 5.0}), 1.0);
  EXPECT_NEAR(dot(v_capped, v_capped), 50.0, 1e-9);
  const auto [full, v_full] = corner_step("");
  EXPECT_EQ(statistic(full, "qp_caps"), 0);
  EXPECT_EQ(statistic(full, "stalled_reflections"), 0);
  EXPECT_GT(statistic(full, "min_gap"), -1e-10);
  EXPECT_NEAR(v_full.x, 5.0, 1e-12);
  EXPECT_NEAR(v_full.y, 0.0, 1e-12);
  EXPECT_NEAR(v_full.z, 5.0, 1e-12);
}

// [constraints.limits]: each limit an integer from 1 to 1e6; a misspelt key is refused
// with the known ones suggested, as every table of the input.
TEST(SolverLimits, InputRefusesBadLimits) {
  auto read = [](const std::string& limits) {
    return testing::input_with_atoms(
        "LimitsInput" + std::to_string(::getpid()), {{{0, 0, 1}, {0, 0, 0}}}, "fff",
        {-10, -10, -10}, {10, 10, 10},
        "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nwalls = [{ type = \"plane\", "
        "point = [0, 0, 0], normal = [0, 0, 1] }]\n" +
            limits + "[integrator]\ntype = \"gvi\"\ntimestep = 0.01\n[run]\nsteps = 0\n");
  };
  const RunInput good = read("limits = { newton = 7, feasibility_rounds = 3 }\n");
  EXPECT_EQ(good.constraints.limits.newton, 7);
  EXPECT_EQ(good.constraints.limits.feasibility_rounds, 3);
  EXPECT_EQ(good.constraints.limits.active_set_rounds, SolverLimits{}.active_set_rounds);
  EXPECT_EQ(good.constraints.limits.qp_iterations, 0);  // absent: 10 n + 10 per solve
  EXPECT_EQ(read("limits = { qp_iterations = 5 }\n").constraints.limits.qp_iterations, 5);
  for (const char* bad : {"limits = { newton = 0 }\n", "limits = { line_search = 2000000 }\n",
                          "limits = { qp_iterations = 0 }\n", "limits = { qp_iterations = -1 }\n",
                          "limits = { midpoint_passes = 1.5 }\n"}) {
    try {
      (void)read(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("limits"), std::string::npos) << e.what();
    }
  }
  try {
    (void)read("limits = { newtn = 3 }\n");
    ADD_FAILURE() << "accepted a misspelt limit";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("newtn"), std::string::npos) << e.what();
  }
}

// Checkpoints written by an earlier deli restore, their counters kept and the newer ones
// zero: before relative_restorations (19 numbers per statistics block) and before the limit
// counters too (15); the current layout round-trips.
TEST(SolverLimits, CheckpointWithoutTheNewerCountersRestores) {
  RunInput input = bipyramid("OldCheckpoint" + std::to_string(::getpid()), "");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  gvi.setup(input.system);
  for (int step = 0; step < 50; ++step) gvi.step(input.system, true);
  const std::vector<double> state = gvi.saved_state();
  const std::size_t n = input.system.particles.size();
  const std::size_t now = ConstraintStatistics::saved_size;
  ASSERT_EQ(state.size(), 2 * now + 2 + 3 * n);
  const auto expected = gvi.take_statistics(Sampler::thermo, true);
  for (const std::size_t before : {ConstraintStatistics::saved_size_without_relative,
                                   ConstraintStatistics::saved_size_without_caps}) {
    std::vector<double> old;
    for (std::size_t block = 0; block < 2; ++block) {
      old.insert(old.end(), state.begin() + block * now, state.begin() + block * now + before);
    }
    old.insert(old.end(), state.begin() + 2 * now, state.end());
    Gvi restored(*input.force_field, input.constraints, input.gvi, input.system.particles);
    restored.restore_state(old, input.system);
    const auto got = restored.take_statistics(Sampler::thermo, true);
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].first, expected[k].first);
      // The newer counters are 0 in this run too.
      EXPECT_EQ(got[k].second, expected[k].second) << got[k].first << ", layout " << before;
    }
  }
  Gvi same(*input.force_field, input.constraints, input.gvi, input.system.particles);
  same.restore_state(state, input.system);
  EXPECT_EQ(same.saved_state(), state);
}

// The implicit midpoint's fixed point (one loop for GVI and the baselines): two LJ atoms
// 1.1 sigma apart moving towards each other need several passes to reach 1e-12; with
// midpoint_passes = 2 the run stops naming the step, the last change and the limit.
TEST(SolverLimits, MidpointPassesHitStopsTheRun) {
  for (const char* integrator :
       {"type = \"gvi\"\nlagrangian = \"midpoint\"", "type = \"direct\"\nscheme = \"midpoint\"",
        "type = \"collision\"\nlagrangian = \"midpoint\""}) {
    RunInput input = testing::input_with_atoms(
        "MidpointPasses" + std::to_string(::getpid()),
        {{{0, 0, 0}, {1, 0, 0}}, {{1.1, 0, 0}, {-1, 0, 0}}}, "fff", {-10, -10, -10}, {10, 10, 10},
        "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\ncoeffs = [{ types = [1, 1], "
        "epsilon = 1.0, sigma = 1.0 }]\n[constraints]\nwalls = [{ type = \"plane\", point = "
        "[0, 0, -5], normal = [0, 0, 1] }]\nlimits = { midpoint_passes = 2 }\n[integrator]\n" +
            std::string(integrator) + "\ntimestep = 0.005\n[run]\nsteps = 0\n");
    std::unique_ptr<Integrator> run = make_integrator(input);
    run->setup(input.system);
    try {
      run->step(input.system, true);
      ADD_FAILURE() << integrator << ": expected the midpoint limit to stop the run";
    } catch (const SimulationError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("step 1:"), std::string::npos) << what;
      EXPECT_NE(what.find("implicit-midpoint fixed point"), std::string::npos) << what;
      EXPECT_NE(what.find("after 2 passes ([constraints.limits] midpoint_passes)"),
                std::string::npos)
          << what;
    }
  }
}

// The feasibility guard's limit: a V of two rods (ends 0.002 and 0.05 above a floor, apex
// 0.6, at rest, gravity, h = 0.1: the free step drops everything by g h^2 / 2 = 0.049).
// Round 0 finds only the low end overlapping; landing it pivots the V about it and sends the
// other end through the floor, landed in round 1. With feasibility_rounds = 1 the second
// landing is not made: the hit is counted in feasibility_caps and the step ends overlapped
// (penetrating_steps); with the default both ends land and nothing overlaps.
TEST(SolverLimits, FeasibilityLimitHitIsCountedAndTheOverlapShown) {
  auto first_step = [](const std::string& limits) {
    const Vec3 low{0, 0, 0.002}, apex{0.8, 0, 0.6}, high{1.6, 0, 0.05};
    char rods[200];
    std::snprintf(rods, sizeof rods,
                  "rods = [{ atoms = [1, 2], length = %.17g }, { atoms = [2, 3], length = "
                  "%.17g }]\n",
                  norm(low - apex), norm(apex - high));
    RunInput input = testing::input_with_atoms(
        "FeasibilityLimit" + std::to_string(::getpid()), {{low, {}}, {apex, {}}, {high, {}}}, "fff",
        {-10, -10, -10}, {10, 10, 10},
        "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\ngravity = [0, 0, "
        "-9.8]\n[constraints]\n" +
            std::string(rods) +
            "walls = [{ type = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }]\n" + limits +
            "[integrator]\ntype = \"gvi\"\ntimestep = 0.1\n[run]\nsteps = 0\n");
    Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
    gvi.setup(input.system);
    gvi.step(input.system, true);
    return gvi.take_statistics();
  };
  const auto capped = first_step("limits = { feasibility_rounds = 1 }\n");
  EXPECT_EQ(statistic(capped, "feasibility_caps"), 1);
  EXPECT_EQ(statistic(capped, "landings"), 1);
  EXPECT_EQ(statistic(capped, "penetrating_steps"), 1);
  EXPECT_LT(statistic(capped, "min_gap"), -1e-10);
  const auto full = first_step("");
  EXPECT_EQ(statistic(full, "feasibility_caps"), 0);
  EXPECT_EQ(statistic(full, "landings"), 2);
  EXPECT_EQ(statistic(full, "penetrating_steps"), 0);
  EXPECT_GT(statistic(full, "min_gap"), -1e-10);
}

// The collision baseline's contact-time limit: a ball dropped from rest at z = 1 onto a floor
// (h = 0.01) meets it in step 46 (t = sqrt(2 / 9.8) = 0.452); with one root-finding
// iteration the bracket stays wider than root_tolerance * h: the hit is counted and the
// ball is put at the bracket's feasible end, above the floor. With the default limit the
// bracket closes: nothing counted.
TEST(SolverLimits, ContactTimeLimitHitIsCountedAtTheFeasibleEnd) {
  auto drop = [](const std::string& limits) {
    RunInput input = testing::input_with_atoms(
        "ContactTimeLimit" + std::to_string(::getpid()), {{{0, 0, 1}, {}}}, "fff", {-10, -10, -10},
        {10, 10, 10},
        "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\ngravity = [0, 0, "
        "-9.8]\n[constraints]\nwalls = [{ type = \"plane\", point = [0, 0, 0], normal = [0, 0, "
        "1] }]\n" +
            limits + "[integrator]\ntype = \"collision\"\ntimestep = 0.01\n[run]\nsteps = 0\n");
    std::unique_ptr<Integrator> run = make_integrator(input);
    run->setup(input.system);
    for (int step = 0; step < 60; ++step) run->step(input.system, true);
    return run->take_statistics();
  };
  const auto capped = drop("limits = { contact_time = 1 }\n");
  EXPECT_GE(statistic(capped, "contact_time_caps"), 1);
  EXPECT_GT(statistic(capped, "min_gap"), -1e-10);
  const auto full = drop("");
  EXPECT_EQ(statistic(full, "contact_time_caps"), 0);
  EXPECT_GT(statistic(full, "min_gap"), -1e-10);
}

}  // namespace
}  // namespace deli
