#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/position_update.hpp"

namespace deli {

// One cluster's position update as plain data (Siconos keeps its problems so): what a run
// writes when the solve fails (`deli-failed-solve-stepN.txt`), what `deli solve-problem`
// and the regression tests under tests/solver_problems/ read back and solve again. The
// numbers are written with 17 significant digits: a problem read back is the same
// problem, bit for bit.
struct PositionProblem {
  std::int64_t step = 0;  // the step that failed (informative)
  double h = 0;
  double tolerance = 0;       // the residual the run asked for (sigma)
  int newton_limit = 0;       // the Newton iterations it allowed
  int line_search_limit = 0;  // and halvings per line search
  Box box;
  std::vector<std::int64_t> ids;  // atom ids of the cluster's particles, for messages
  LocalCluster cluster;           // rows in local numbering, inverse masses
  std::vector<bool> equality;     // per row: held as an equality (else complementarity)
  std::vector<Vec3> q, x0;        // start positions, unconstrained end positions
  // What the failed solve reported (informative: a re-solve reports its own).
  double failed_residual = 0;
  int failed_iterations = 0;
};

void write_position_problem(std::ostream& out, const PositionProblem& problem);
// Writes the problem to `path`; returns "is in PATH", or that PATH could not be written and
// why (for the run's failure message).
std::string save_position_problem(const std::string& path, const PositionProblem& problem);
// Reads a problem written by write_position_problem. Throws InputError naming the file, the
// line and what was expected.
PositionProblem read_position_problem(const std::string& path);

// Solves the problem as the run did, with its tolerance and Newton limit (or `newton_limit`
// when positive).
[[nodiscard]] PositionUpdate solve_position_problem(const PositionProblem& problem,
                                                    int newton_limit = 0);
// What a solve of the problem gave, for a reader: converged or not, iterations, residual,
// and each row's gap and impulse at the end (atom ids as in the run).
std::string describe_position_solve(const PositionProblem& problem, const PositionUpdate& solved);

}  // namespace deli
