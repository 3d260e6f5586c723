#include "solvers/chain_projection.hpp"

#include "solvers/tridiagonal.hpp"

namespace deli {

bool project_out_chains(const LocalCluster& cluster, const std::vector<int>& equality_rows,
                        const std::vector<Vec3>& x, const Box& box, Eigen::MatrixXd& N,
                        Eigen::MatrixXd& Y) {
  const auto m = static_cast<Eigen::Index>(equality_rows.size());
  const std::vector<double>& w = cluster.inverse_mass;
  // Chains: a particle's rows lie at most one apart in the order given, so rows k and l
  // share no particle unless |k - l| <= 1.
  std::vector<int> first_row(cluster.size(), -1);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Constraint& c = cluster.rows[equality_rows[k]];
    if (c.j < 0) return false;
    for (const std::int32_t p : {c.i, c.j}) {
      if (first_row[p] < 0) {
        first_row[p] = static_cast<int>(k);
      } else if (k - first_row[p] > 1) {
        return false;
      }
    }
  }
  // Row k's gradient: +u_k on particle i, -u_k on particle j.
  std::vector<Vec3> u(static_cast<std::size_t>(m));
  for (Eigen::Index k = 0; k < m; ++k) {
    u[k] = evaluate(cluster.rows[equality_rows[k]], x.data(), box).u;
  }
  auto sign = [](const Constraint& c, std::int32_t p) { return c.i == p ? 1.0 : -1.0; };
  Tridiagonal a;
  a.resize_zero(m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Constraint& c = cluster.rows[equality_rows[k]];
    a.diagonal(k) = (w[c.i] + w[c.j]) * norm2(u[k]);
    if (k + 1 == m) continue;
    const Constraint& next = cluster.rows[equality_rows[k + 1]];
    double coupling = 0.0;
    for (const std::int32_t p : {c.i, c.j}) {
      if (p == next.i || p == next.j)
        coupling += w[p] * sign(c, p) * sign(next, p) * dot(u[k], u[k + 1]);
    }
    a.upper(k) = coupling;
    a.lower(k + 1) = coupling;
  }
  const Eigen::Index columns = N.cols();
  Eigen::MatrixXd solved(m, columns);
  Eigen::VectorXd rhs(m), y, scratch;
  auto at = [&](Eigen::Index column, std::int32_t p) {
    return Vec3{N(3 * p, column), N(3 * p + 1, column), N(3 * p + 2, column)};
  };
  for (Eigen::Index col = 0; col < columns; ++col) {
    for (Eigen::Index k = 0; k < m; ++k) {
      const Constraint& c = cluster.rows[equality_rows[k]];
      rhs(k) = w[c.i] * dot(u[k], at(col, c.i)) - w[c.j] * dot(u[k], at(col, c.j));
    }
    if (!solve_tridiagonal(a, rhs, y, scratch)) return false;
    solved.col(col) = y;
  }
  for (Eigen::Index col = 0; col < columns; ++col) {
    for (Eigen::Index k = 0; k < m; ++k) {
      const Constraint& c = cluster.rows[equality_rows[k]];
      const Vec3 along = u[k] * solved(k, col);
      for (int d = 0; d < 3; ++d) {
        N(3 * c.i + d, col) -= along[d];
        N(3 * c.j + d, col) += along[d];
      }
    }
  }
  Y = std::move(solved);
  return true;
}

}  // namespace deli
