#include "solvers/nonnegative_qp.hpp"

#include <vector>

namespace deli {

namespace {
// Least-norm solution of Q_PP s = -c_P over the passive set.
Eigen::VectorXd solve_passive(const Eigen::MatrixXd& Q, const Eigen::VectorXd& c,
                              const std::vector<int>& passive) {
  const auto n = static_cast<Eigen::Index>(passive.size());
  Eigen::MatrixXd A(n, n);
  Eigen::VectorXd b(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    b(r) = -c(passive[r]);
    for (Eigen::Index s = 0; s < n; ++s) A(r, s) = Q(passive[r], passive[s]);
  }
  return A.completeOrthogonalDecomposition().solve(b);
}
}  // namespace

SolverStatus solve_nonnegative_qp(const Eigen::MatrixXd& Q, const Eigen::VectorXd& c,
                                  Eigen::VectorXd& x, double tolerance, int max_iterations) {
  const auto n = c.size();
  if (max_iterations <= 0) max_iterations = 10 * static_cast<int>(n) + 10;
  x = Eigen::VectorXd::Zero(n);
  std::vector<bool> in_passive(static_cast<std::size_t>(n), false);
  // A variable whose entry makes no progress (rounding at a degenerate vertex) is not
  // offered again until x changes: the guard against cycling.
  std::vector<bool> blocked(static_cast<std::size_t>(n), false);
  SolverStatus status;
  for (; status.iterations < max_iterations; ++status.iterations) {
    const Eigen::VectorXd w = -(Q * x + c);  // descent direction of the objective
    Eigen::Index enter = -1;
    double best = tolerance;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!in_passive[i] && !blocked[i] && w(i) > best) best = w(i), enter = i;
    }
    if (enter < 0) {
      status.converged = true;
      break;
    }
    in_passive[enter] = true;
    // Inner loop: move towards the unconstrained minimiser on the passive set, stopping
    // where a passive variable reaches zero and releasing it.
    for (int inner = 0; inner <= n; ++inner) {
      std::vector<int> passive;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (in_passive[i]) passive.push_back(static_cast<int>(i));
      }
      const Eigen::VectorXd s = solve_passive(Q, c, passive);
      bool feasible = true;
      double alpha = 1.0;
      for (std::size_t k = 0; k < passive.size(); ++k) {
        if (s(static_cast<Eigen::Index>(k)) <= 0.0) {
          feasible = false;
          const double xi = x(passive[k]);
          alpha = std::min(alpha, xi / (xi - s(static_cast<Eigen::Index>(k))));
        }
      }
      if (feasible) {
        for (std::size_t k = 0; k < passive.size(); ++k) {
          x(passive[k]) = s(static_cast<Eigen::Index>(k));
        }
        std::fill(blocked.begin(), blocked.end(), false);
        break;
      }
      if (inner == 0 && alpha <= 0.0) {
        in_passive[enter] = false;
        blocked[enter] = true;
        break;
      }
      for (std::size_t k = 0; k < passive.size(); ++k) {
        const int i = passive[k];
        x(i) += alpha * (s(static_cast<Eigen::Index>(k)) - x(i));
        if (x(i) <= 0.0) {
          x(i) = 0.0;
          in_passive[i] = false;
        }
      }
    }
  }
  const Eigen::VectorXd w = -(Q * x + c);
  status.residual = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    status.residual = std::max(status.residual, x(i) > 0 ? std::abs(w(i)) : std::max(0.0, w(i)));
  }
  return status;
}

}  // namespace deli
