#include "solvers/tridiagonal.hpp"

namespace deli {

bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
  Eigen::VectorXd c;
  return solve_tridiagonal(a, rhs, x, c);
}

bool solve_tridiagonal(const Tridiagonal& a, const Eigen::VectorXd& rhs, Eigen::VectorXd& x,
                       Eigen::VectorXd& c) {
  const Eigen::Index n = a.size();
  x.resize(n);
  c.resize(n);
  return solve_tridiagonal_twisted(
      n, [&](Eigen::Index k) { return a.lower(k); }, [&](Eigen::Index k) { return a.diagonal(k); },
      [&](Eigen::Index k) { return a.upper(k); }, [&](Eigen::Index k) { return rhs(k); }, x.data(),
      c.data());
}

}  // namespace deli
