// The O(n) tridiagonal solve (elimination from both ends, no pivoting) against a second method,
// Eigen's dense LU with partial pivoting, on the Newton matrices of random rod chains: to
// round-off. A vanishing pivot (dependent rows) is reported, not divided by.
#include "solvers/tridiagonal.hpp"

#include <gtest/gtest.h>

#include <random>

namespace deli {
namespace {

// A chain of n rods with unit directions u_k (random walk), masses in [0.5, 2]: the RATTLE
// matrix A(k, k) = (w_k + w_{k+1}), A(k, k+1) = A(k+1, k) = -w_{k+1} u_k . u_{k+1}, and, for
// the SHAKE Newton matrix, the directions at the start (b) differing slightly from those at
// the end (a): A(k, l) = sum over shared beads of w s_k s_l a_k . b_l, not symmetric.
Tridiagonal chain_matrix(Eigen::Index n, double tilt, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> mass(0.5, 2.0);
  auto unit = [&] {
    Eigen::Vector3d v(normal(rng), normal(rng), normal(rng));
    return Eigen::Vector3d(v.normalized());
  };
  std::vector<Eigen::Vector3d> a, b;
  for (Eigen::Index k = 0; k < n; ++k) {
    b.push_back(unit());
    a.push_back((b.back() + tilt * unit()).normalized());
  }
  std::vector<double> w;
  for (Eigen::Index k = 0; k <= n; ++k) w.push_back(1.0 / mass(rng));
  Tridiagonal t;
  t.resize_zero(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    t.diagonal(k) = (w[k] + w[k + 1]) * a[k].dot(b[k]);
    if (k + 1 < n) {
      t.upper(k) = -w[k + 1] * a[k].dot(b[k + 1]);
      t.lower(k + 1) = -w[k + 1] * a[k + 1].dot(b[k]);
    }
  }
  return t;
}

Eigen::MatrixXd dense(const Tridiagonal& t) {
  const Eigen::Index n = t.size();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    m(k, k) = t.diagonal(k);
    if (k + 1 < n) {
      m(k, k + 1) = t.upper(k);
      m(k + 1, k) = t.lower(k + 1);
    }
  }
  return m;
}

TEST(Tridiagonal, SolvesChainSystemsAsDenseLU) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  for (Eigen::Index n : {1, 2, 3, 39, 80}) {
    for (double tilt : {0.0, 0.05}) {
      const Tridiagonal t = chain_matrix(n, tilt, static_cast<std::uint64_t>(n) + 11);
      Eigen::VectorXd rhs(n);
      for (Eigen::Index k = 0; k < n; ++k) rhs(k) = normal(rng);
      Eigen::VectorXd x;
      ASSERT_TRUE(solve_tridiagonal(t, rhs, x)) << "n " << n;
      const Eigen::MatrixXd m = dense(t);
      const Eigen::VectorXd reference = m.partialPivLu().solve(rhs);
      // Both backward stable on these well-conditioned (diagonally dominant on average)
      // matrices: they agree to a few ulps of the solution's size times the condition.
      const double scale = reference.lpNorm<Eigen::Infinity>();
      EXPECT_LE((x - reference).lpNorm<Eigen::Infinity>(), 1e-12 * scale) << "n " << n;
      EXPECT_LE((m * x - rhs).lpNorm<Eigen::Infinity>(), 1e-13 * rhs.lpNorm<Eigen::Infinity>());
    }
  }
}

TEST(Tridiagonal, ReportsAVanishingPivot) {
  // Two equal rows: singular; the second pivot cancels exactly.
  Tridiagonal t;
  t.resize_zero(2);
  t.diagonal << 1.0, 1.0;
  t.upper(0) = 1.0;
  t.lower(1) = 1.0;
  Eigen::VectorXd x;
  EXPECT_FALSE(solve_tridiagonal(t, Eigen::VectorXd::Ones(2), x));
}

}  // namespace
}  // namespace deli
