#pragma once

namespace deli {

// What every iterative solve reports (Siconos style): callers decide what a failure means,
// and report it with the step and the cluster; nothing is swallowed.
struct SolverStatus {
  bool converged = false;
  int iterations = 0;
  double residual = 0;
};

}  // namespace deli
