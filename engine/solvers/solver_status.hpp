#pragma once

#include <Eigen/Dense>
#include <limits>

namespace deli {

// What every iterative solve reports (Siconos style): callers decide what a failure means,
// and report it with the step and the cluster; nothing is swallowed. [[nodiscard]]: a
// function returning a status cannot be called as if it could not fail.
struct [[nodiscard]] SolverStatus {
  bool converged = false;
  int iterations = 0;
  double residual = 0;
};

// max |r_k|, or +inf when an entry is not finite: Eigen's maximum skips NaN, so a NaN
// residual would pass for a converged one.
inline double residual_norm(const Eigen::VectorXd& r) {
  return r.allFinite() ? r.lpNorm<Eigen::Infinity>() : std::numeric_limits<double>::infinity();
}

}  // namespace deli
