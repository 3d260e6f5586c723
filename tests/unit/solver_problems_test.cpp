// The collection of failed position updates (tests/solver_problems/, as Siconos keeps its
// problem collection): each file is a problem a run dumped when its solve failed; the
// current solver, with the run's default limits, must solve every one. Also: a problem
// written and read back is the same problem bit for bit, and a damaged file is refused
// naming its line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "constraints/constraint_set.hpp"
#include "core/error.hpp"
#include "solvers/position_problem.hpp"
#include "support/shell.hpp"

namespace deli {
namespace {

const std::string kCollection = std::string(DELI_SOURCE_DIR) + "/tests/solver_problems";

std::vector<std::string> collection() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(kCollection)) {
    if (entry.path().extension() == ".txt") files.push_back(entry.path().filename().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

class SolverProblem : public ::testing::TestWithParam<std::string> {};

// Solved: every equality row within the problem's tolerance, every inequality row not
// overlapping beyond it, its impulse non-negative and zero where it does not touch
// (complementarity, Fischer-Burmeister's residual below the tolerance in length units).
// A problem named infeasible_* has no solution (its comment says why): it must be reported
// unconverged, with finite positions and impulses no larger than moving an atom by one
// sigma (h |z| / m < 1), never passed off as solved or left with runaway multipliers.
TEST_P(SolverProblem, IsSolvedByTheCurrentSolver) {
  const PositionProblem problem = read_position_problem(kCollection + "/" + GetParam());
  const SolverLimits limits;
  const PositionUpdate solved = solve_position_problem(problem, limits.newton);
  if (GetParam().rfind("infeasible_", 0) == 0) {
    EXPECT_FALSE(solved.status.converged) << describe_position_solve(problem, solved);
    EXPECT_GT(solved.status.residual, problem.tolerance);
    const double largest_inverse_mass =
        *std::max_element(problem.cluster.inverse_mass.begin(), problem.cluster.inverse_mass.end());
    EXPECT_LT(problem.h * solved.z.lpNorm<Eigen::Infinity>() * largest_inverse_mass, 1.0)
        << describe_position_solve(problem, solved);
    for (const Vec3& x : solved.x) EXPECT_TRUE(std::isfinite(x.x + x.y + x.z));
    return;
  }
  ASSERT_TRUE(solved.status.converged) << describe_position_solve(problem, solved);
  EXPECT_LE(solved.status.residual, problem.tolerance);
  for (std::size_t r = 0; r < problem.cluster.rows.size(); ++r) {
    const Constraint& c = problem.cluster.rows[r];
    const double gap = evaluate(c, solved.x.data(), problem.box).gap;
    if (problem.equality[r]) {
      EXPECT_LE(std::abs(gap), problem.tolerance) << "row " << r;
    } else {
      const double scale = problem.h * (problem.cluster.inverse_mass[c.i] +
                                        (c.j >= 0 ? problem.cluster.inverse_mass[c.j] : 0.0));
      const double impulse_length = scale * solved.z(static_cast<Eigen::Index>(r));
      EXPECT_GE(gap, -problem.tolerance) << "row " << r;
      EXPECT_GE(impulse_length, -problem.tolerance) << "row " << r;
      EXPECT_LE(std::min(std::abs(gap), std::abs(impulse_length)), problem.tolerance)
          << "row " << r;
    }
  }
}

std::string problem_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param.substr(0, info.param.size() - 4);
  for (char& ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Collection, SolverProblem, ::testing::ValuesIn(collection()),
                         problem_name);

TEST(SolverProblemCollection, IsNotEmpty) {
  EXPECT_GE(collection().size(), 3u);
}

bool same(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}
bool same(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (!same(a[k], b[k])) return false;
  }
  return true;
}

std::string temp_path(const std::string& test) {
  return "/tmp/deli-" + test + "-" + std::to_string(::getpid()) + ".txt";
}

// Every number round trips exactly (17 significant digits), every row kind and the box.
TEST(SolverProblemFile, RoundTripsBitForBit) {
  PositionProblem p;
  p.step = 1234;
  p.h = 0.1 / 3.0;
  p.tolerance = 1e-12;
  p.newton_limit = 7;
  p.line_search_limit = 34;
  p.failed_residual = 1.0 / 7.0;
  p.failed_iterations = 7;
  p.box = Box({-1.0 / 3.0, 0, 0}, {10.0 / 3.0, 5, 6}, {true, false, true});
  const ConstraintKind kinds[] = {ConstraintKind::rod,           ConstraintKind::anchor,
                                  ConstraintKind::sphere_pair,   ConstraintKind::plane,
                                  ConstraintKind::inside_sphere, ConstraintKind::outside_sphere,
                                  ConstraintKind::linear_pair};
  for (int k = 0; k < 3; ++k) {
    p.ids.push_back(100 + k);
    p.cluster.particles.push_back(k);
    p.cluster.inverse_mass.push_back(1.0 / (1.0 + k / 3.0));
    p.q.push_back({0.1 * k, std::sqrt(2.0) * k, -1.0 / (k + 3.0)});
    p.x0.push_back({0.1 * k + 1e-17, std::sqrt(3.0), 1e-300});
  }
  int r = 0;
  for (ConstraintKind kind : kinds) {
    Constraint c;
    c.kind = kind;
    c.i = r % 3;
    c.j = is_pair(kind) ? (r + 1) % 3 : -1;
    c.length = 1.0 / (r + 3.0);
    c.point = {1.0 / 7.0, 2.0 / 7.0, 3.0 / 7.0};
    c.normal = {0.6, 0.0, 0.8};
    p.cluster.rows.push_back(c);
    p.cluster.global_rows.push_back(r);
    p.equality.push_back(is_equality(kind));
    ++r;
  }
  const std::string path = temp_path("RoundTripsBitForBit");
  ASSERT_EQ(save_position_problem(path, p), "is in " + path);
  const PositionProblem back = read_position_problem(path);
  std::remove(path.c_str());
  EXPECT_EQ(back.step, p.step);
  EXPECT_EQ(back.h, p.h);
  EXPECT_EQ(back.tolerance, p.tolerance);
  EXPECT_EQ(back.newton_limit, p.newton_limit);
  EXPECT_EQ(back.line_search_limit, p.line_search_limit);
  EXPECT_EQ(back.failed_residual, p.failed_residual);
  EXPECT_EQ(back.failed_iterations, p.failed_iterations);
  EXPECT_TRUE(same(back.box.lo(), p.box.lo()));
  EXPECT_TRUE(same(back.box.hi(), p.box.hi()));
  EXPECT_EQ(back.box.periodic(), p.box.periodic());
  EXPECT_EQ(back.ids, p.ids);
  EXPECT_EQ(back.cluster.inverse_mass, p.cluster.inverse_mass);
  EXPECT_TRUE(same(back.q, p.q));
  EXPECT_TRUE(same(back.x0, p.x0));
  EXPECT_EQ(back.equality, p.equality);
  ASSERT_EQ(back.cluster.rows.size(), p.cluster.rows.size());
  for (std::size_t k = 0; k < p.cluster.rows.size(); ++k) {
    EXPECT_TRUE(same_row(back.cluster.rows[k], p.cluster.rows[k])) << k;
  }
}

// A damaged file is refused with its name, the line and what was expected there.
TEST(SolverProblemFile, DamagedFileNamesTheLine) {
  const std::string path = temp_path("DamagedFileNamesTheLine");
  {
    std::ofstream out(path);
    out << "# a problem\nstep 3\nh 0.01\ntolerance 1e-12\nnewton_limit 50\n"
           "line_search_limit 34\nfailed 1e-3 50\nbox 0 0 0 1 1 1 0 0 0\nparticles 1\n"
           "7 1.0 0 0 0 0 0 0\nrows 1\nhinge equality 0 -1 1 0 0 0 0 0 1\n";
  }
  try {
    (void)read_position_problem(path);
    ADD_FAILURE() << "a row of unknown kind was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path + ":12:"), std::string::npos) << what;
    EXPECT_NE(what.find("unknown row kind 'hinge'"), std::string::npos) << what;
  }
  std::remove(path.c_str());
  EXPECT_THROW((void)read_position_problem(path), InputError);  // gone: cannot be read
}

// `deli solve-problem FILE [--newton N]`: exit status 0 when the problem converges, 3 when
// it does not (the dumped limit reproduces the run's failure), 1 for a bad argument.
TEST(SolveProblemCommand, ReportsConvergenceByExitStatus) {
  const std::string deli = DELI_BINARY;
  const std::string chain = kCollection + "/slit_chain_newton_limit.txt";
  const testing::ShellResult limited = testing::run_shell(deli + " solve-problem " + chain);
  EXPECT_EQ(limited.status, 3) << limited.output;
  EXPECT_NE(limited.output.find("NOT converged after 1 Newton iterations"), std::string::npos)
      << limited.output;
  const testing::ShellResult solved =
      testing::run_shell(deli + " solve-problem " + chain + " --newton 50");
  EXPECT_EQ(solved.status, 0) << solved.output;
  EXPECT_NE(solved.output.find("converged after"), std::string::npos) << solved.output;
  const testing::ShellResult bad =
      testing::run_shell(deli + " solve-problem " + chain + " --newton 0");
  EXPECT_EQ(bad.status, 1) << bad.output;
  EXPECT_NE(bad.output.find("--newton 0"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace deli
