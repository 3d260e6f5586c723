#include "solvers/tridiagonal.hpp"

#include <cmath>

namespace deli {

bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
  Eigen::VectorXd c;
  return solve_tridiagonal(a, rhs, x, c);
}

bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs, Eigen::VectorXd& x,
                       Eigen::VectorXd& c) {
  const Eigen::Index n = a.size();
  x.resize(n);
  if (n == 0) return true;
  // Forward sweep: c'(k) = upper(k) / pivot(k), x holds d'(k); back substitution in place.
  c.resize(n);
  // A pivot lost to cancellation (relative to its diagonal entry) means dependent rows.
  auto vanishes = [&](double pivot, Eigen::Index k) {
    return !(std::abs(pivot) > 1e-12 * std::abs(a.diagonal(k)));
  };
  double pivot = a.diagonal(0);
  if (vanishes(pivot, 0)) return false;
  c(0) = n > 1 ? a.upper(0) / pivot : 0.0;
  x(0) = rhs(0) / pivot;
  for (Eigen::Index k = 1; k < n; ++k) {
    pivot = a.diagonal(k) - a.lower(k) * c(k - 1);
    if (vanishes(pivot, k)) return false;
    c(k) = k + 1 < n ? a.upper(k) / pivot : 0.0;
    x(k) = (rhs(k) - a.lower(k) * x(k - 1)) / pivot;
  }
  for (Eigen::Index k = n - 2; k >= 0; --k) x(k) -= c(k) * x(k + 1);
  return x.allFinite();
}

}  // namespace deli
