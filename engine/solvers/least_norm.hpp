#pragma once

#include <Eigen/Dense>

namespace deli {

// Least-norm solutions x of A x = b where A may be rank-deficient (dependent rows: a rigid
// loop, a contact repeating a rod): the directions whose pivots fall below the threshold,
// relative to the largest, are dropped. Eigen's complete orthogonal decomposition, its
// template compiled here once: it was about 6.5 of the 11 CPU s of each of the four solver
// files that instantiated it (g++ -O3, measured), on every build of each.
class LeastNorm {
 public:
  LeastNorm();
  ~LeastNorm();
  LeastNorm(LeastNorm&&) noexcept;
  LeastNorm& operator=(LeastNorm&&) noexcept;

  // threshold < 0: Eigen's default (machine epsilon times the size).
  void compute(const Eigen::MatrixXd& A, double threshold = -1.0);
  // x = A^+ b for the A of the last compute (x may be kept between calls: no reallocation at
  // the same size).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  void solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;

 private:
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> decomposition_;
};

// A^+ b in one call, with Eigen's default threshold.
Eigen::VectorXd least_norm_solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b);
void least_norm_solve(const Eigen::MatrixXd& A, const Eigen::MatrixXd& b, Eigen::MatrixXd& x);

}  // namespace deli
