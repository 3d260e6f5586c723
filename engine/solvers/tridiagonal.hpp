#pragma once

#include <Eigen/Dense>
#include <cmath>

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

// Solves A x = rhs by Gaussian elimination without pivoting, stable for the (near)
// symmetric positive definite matrices of rod chains. Returns false when a pivot vanishes
// or the solution is not finite: the caller falls back to a dense solve.
[[nodiscard]] bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs,
                                     Eigen::VectorXd& x);
// The same with the sweep's scratch vector `c` kept by the caller (no allocation).
[[nodiscard]] bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs,
                                     Eigen::VectorXd& x, Eigen::VectorXd& c);

// The elimination behind solve_tridiagonal, with the entries of A and rhs given by functions
// of the row (lower(k) = A(k, k-1), upper(k) = A(k, k+1), each asked once) so that a caller
// can make them as the sweep reaches them: every caller gets the same operations in the same
// order, hence the same bits. A twisted factorisation: rows 0.. are eliminated downwards
// and rows n-1.. upwards at the same time, meeting at row n/2, then both halves are
// substituted back outwards. A Thomas sweep waits at every row on the previous row's
// division; two independent sweeps of half the length overlap those waits. One division per
// row (its pivot's reciprocal). x and c point to n doubles each (c: scratch).
template <class Lower, class Diagonal, class Upper, class Rhs>
[[nodiscard]] bool solve_tridiagonal_twisted(Eigen::Index n, const Lower& lower,
                                             const Diagonal& diagonal, const Upper& upper,
                                             const Rhs& rhs, double* x, double* c) {
  if (n == 0) return true;
  // A pivot lost to cancellation (relative to its diagonal entry) means dependent rows.
  auto vanishes = [](double pivot, double diagonal_entry) {
    return !(std::abs(pivot) > 1e-12 * std::abs(diagonal_entry));
  };
  const Eigen::Index meet = n / 2;
  const Eigen::Index below = n - 1 - meet;  // rows after the meeting row (<= meet)
  bool regular = true;
  // Downwards, row k < meet becomes x_k + c_k x_{k+1} = x[k]; upwards, row k > meet becomes
  // c_k x_{k-1} + x_k = x[k].
  for (Eigen::Index step = 0; step < meet; ++step) {
    {
      const Eigen::Index k = step;
      const double d = diagonal(k);
      double pivot = d, y = rhs(k);
      if (k > 0) {
        const double l = lower(k);
        pivot = d - l * c[k - 1];
        y -= l * x[k - 1];
      }
      regular = regular && !vanishes(pivot, d);
      const double reciprocal = 1.0 / pivot;
      c[k] = upper(k) * reciprocal;
      x[k] = y * reciprocal;
    }
    if (step < below) {
      const Eigen::Index k = n - 1 - step;
      const double d = diagonal(k);
      double pivot = d, y = rhs(k);
      if (k < n - 1) {
        const double u = upper(k);
        pivot = d - u * c[k + 1];
        y -= u * x[k + 1];
      }
      regular = regular && !vanishes(pivot, d);
      const double reciprocal = 1.0 / pivot;
      c[k] = lower(k) * reciprocal;
      x[k] = y * reciprocal;
    }
  }
  {
    const Eigen::Index k = meet;
    const double d = diagonal(k);
    double pivot = d, y = rhs(k);
    if (k > 0) {
      const double l = lower(k);
      pivot -= l * c[k - 1];
      y -= l * x[k - 1];
    }
    if (k < n - 1) {
      const double u = upper(k);
      pivot -= u * c[k + 1];
      y -= u * x[k + 1];
    }
    regular = regular && !vanishes(pivot, d);
    x[k] = y / pivot;
  }
  if (!regular) return false;
  bool finite = std::isfinite(x[meet]);
  for (Eigen::Index step = 1; step <= meet; ++step) {
    const Eigen::Index up = meet - step;
    x[up] -= c[up] * x[up + 1];
    finite = finite && std::isfinite(x[up]);
    if (step <= below) {
      const Eigen::Index down = meet + step;
      x[down] -= c[down] * x[down - 1];
      finite = finite && std::isfinite(x[down]);
    }
  }
  return finite;
}

}  // namespace deli
