#include "solvers/least_norm.hpp"

namespace deli {

LeastNorm::LeastNorm() = default;
LeastNorm::~LeastNorm() = default;
LeastNorm::LeastNorm(LeastNorm&&) noexcept = default;
LeastNorm& LeastNorm::operator=(LeastNorm&&) noexcept = default;

void LeastNorm::compute(const Eigen::MatrixXd& A, double threshold) {
  if (threshold < 0.0) {
    decomposition_.setThreshold(Eigen::Default);
  } else {
    decomposition_.setThreshold(threshold);
  }
  decomposition_.compute(A);
}

void LeastNorm::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  x = decomposition_.solve(b);
}

void LeastNorm::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  x = decomposition_.solve(b);
}

Eigen::VectorXd least_norm_solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  LeastNorm least_norm;
  least_norm.compute(A);
  Eigen::VectorXd x;
  least_norm.solve(b, x);
  return x;
}

void least_norm_solve(const Eigen::MatrixXd& A, const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  LeastNorm least_norm;
  least_norm.compute(A);
  least_norm.solve(b, x);
}

}  // namespace deli
