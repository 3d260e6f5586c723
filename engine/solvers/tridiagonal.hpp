#pragma once

#include <Eigen/Dense>

namespace deli {

// A square tridiagonal matrix by its three bands: lower(k) = A(k, k-1) (lower(0) unused),
// diagonal(k) = A(k, k), upper(k) = A(k, k+1) (upper(n-1) unused). The rods of a linear
// chain, numbered along it, couple only neighbouring rods: their constraint matrices
// are tridiagonal and solve in O(n), as ILVES does inside GROMACS.
struct Tridiagonal {
  Eigen::VectorXd lower, diagonal, upper;
  void resize_zero(Eigen::Index n) {
    lower.setZero(n);
    diagonal.setZero(n);
    upper.setZero(n);
  }
  Eigen::Index size() const { return diagonal.size(); }
};

// Solves A x = rhs by Gaussian elimination without pivoting (the Thomas algorithm), stable
// for the (near) symmetric positive definite matrices of rod chains. Returns false when a
// pivot vanishes or the solution is not finite: the caller falls back to a dense solve.
[[nodiscard]] bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs,
                                     Eigen::VectorXd& x);
// The same with the sweep's scratch vector `c` kept by the caller (no allocation).
[[nodiscard]] bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs,
                                     Eigen::VectorXd& x, Eigen::VectorXd& c);

}  // namespace deli
