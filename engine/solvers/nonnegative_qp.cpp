#include "solvers/nonnegative_qp.hpp"

#include <vector>

#include "solvers/least_norm.hpp"

namespace deli {

namespace {
// The least-norm solve of one passive-set size, its objects kept between calls: the passive
// set grows and shrinks within a solve, and an object kept per size never reallocates.
// Sizes above kSizesKeptApart (large clusters, rare) share one, so that the kept memory
// stays that of the largest solve.
constexpr std::size_t kSizesKeptApart = 16;
struct PassiveSolve {
  Eigen::MatrixXd A;
  Eigen::VectorXd b, s;
  LeastNorm decomposition;
};

// The solver's vectors and solves, kept between calls: reflections solve many small
// problems of recurring sizes. Each call overwrites what it reads.
struct QpScratch {
  std::vector<char> in_passive, blocked;
  std::vector<int> passive;
  Eigen::VectorXd Qx, w;
  // Index: the passive-set size, 0 for every size above kSizesKeptApart.
  std::vector<PassiveSolve> by_size = std::vector<PassiveSolve>(kSizesKeptApart + 1);
};

// Least-norm solution s of Q_PP s = -c_P over the passive set.
const Eigen::VectorXd& solve_passive(const Eigen::MatrixXd& Q, const Eigen::VectorXd& c,
                                     QpScratch& scratch) {
  const std::vector<int>& passive = scratch.passive;
  const auto n = static_cast<Eigen::Index>(passive.size());
  PassiveSolve& solve = scratch.by_size[passive.size() <= kSizesKeptApart ? passive.size() : 0];
  Eigen::MatrixXd& A = solve.A;
  Eigen::VectorXd& b = solve.b;
  A.resize(n, n);
  b.resize(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    b(r) = -c(passive[r]);
    for (Eigen::Index s = 0; s < n; ++s) A(r, s) = Q(passive[r], passive[s]);
  }
  solve.decomposition.compute(A);
  solve.decomposition.solve(b, solve.s);
  return solve.s;
}

// w = -(Q x + c), the descent direction of the objective.
void descent(const Eigen::MatrixXd& Q, const Eigen::VectorXd& c, const Eigen::VectorXd& x,
             QpScratch& scratch) {
  scratch.Qx.noalias() = Q * x;
  scratch.w = -(scratch.Qx + c);
}
}  // namespace

SolverStatus solve_nonnegative_qp(const Eigen::MatrixXd& Q, const Eigen::VectorXd& c,
                                  Eigen::VectorXd& x, double tolerance, int max_iterations) {
  thread_local QpScratch scratch;
  const auto n = c.size();
  if (max_iterations <= 0) max_iterations = 10 * static_cast<int>(n) + 10;
  x.setZero(n);
  std::vector<char>& in_passive = scratch.in_passive;
  in_passive.assign(static_cast<std::size_t>(n), 0);
  // A variable whose entry makes no progress (rounding at a degenerate vertex) is not
  // offered again until x changes: the guard against cycling.
  std::vector<char>& blocked = scratch.blocked;
  blocked.assign(static_cast<std::size_t>(n), 0);
  const Eigen::VectorXd& w = scratch.w;
  std::vector<int>& passive = scratch.passive;
  SolverStatus status;
  for (; status.iterations < max_iterations; ++status.iterations) {
    descent(Q, c, x, scratch);
    Eigen::Index enter = -1;
    double best = tolerance;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!in_passive[i] && !blocked[i] && w(i) > best) best = w(i), enter = i;
    }
    if (enter < 0) {
      status.converged = true;
      break;
    }
    in_passive[enter] = 1;
    // Inner loop: move towards the unconstrained minimiser on the passive set, stopping
    // where a passive variable reaches zero and releasing it.
    for (int inner = 0; inner <= n; ++inner) {
      passive.clear();
      for (Eigen::Index i = 0; i < n; ++i) {
        if (in_passive[i]) passive.push_back(static_cast<int>(i));
      }
      const Eigen::VectorXd& s = solve_passive(Q, c, scratch);
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
        std::fill(blocked.begin(), blocked.end(), 0);
        break;
      }
      if (inner == 0 && alpha <= 0.0) {
        in_passive[enter] = 0;
        blocked[enter] = 1;
        break;
      }
      for (std::size_t k = 0; k < passive.size(); ++k) {
        const int i = passive[k];
        x(i) += alpha * (s(static_cast<Eigen::Index>(k)) - x(i));
        if (x(i) <= 0.0) {
          x(i) = 0.0;
          in_passive[i] = 0;
        }
      }
    }
  }
  descent(Q, c, x, scratch);
  status.residual = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    status.residual = std::max(status.residual, x(i) > 0 ? std::abs(w(i)) : std::max(0.0, w(i)));
  }
  return status;
}

}  // namespace deli
