#include "solvers/cluster_matrices.hpp"

namespace deli {

Eigen::MatrixXd gradient_matrix(const LocalCluster& cluster, const std::vector<int>& rows,
                                const std::vector<Vec3>& x, const Box& box) {
  const auto n = static_cast<Eigen::Index>(cluster.size());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * n, static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Constraint& c = cluster.rows[rows[k]];
    const Vec3 u = evaluate(c, x.data(), box).u;
    const auto col = static_cast<Eigen::Index>(k);
    for (int a = 0; a < 3; ++a) {
      G(3 * c.i + a, col) += u[a];
      if (c.j >= 0) G(3 * c.j + a, col) -= u[a];
    }
  }
  return G;
}

Eigen::VectorXd inverse_mass_diagonal(const LocalCluster& cluster) {
  Eigen::VectorXd w(3 * static_cast<Eigen::Index>(cluster.size()));
  for (std::size_t p = 0; p < cluster.size(); ++p) {
    for (int a = 0; a < 3; ++a) w(3 * static_cast<Eigen::Index>(p) + a) = cluster.inverse_mass[p];
  }
  return w;
}

Eigen::VectorXd flatten(const std::vector<Vec3>& v) {
  Eigen::VectorXd out(3 * static_cast<Eigen::Index>(v.size()));
  for (std::size_t p = 0; p < v.size(); ++p) {
    for (int a = 0; a < 3; ++a) out(3 * static_cast<Eigen::Index>(p) + a) = v[p][a];
  }
  return out;
}

std::vector<Vec3> unflatten(const Eigen::VectorXd& v) {
  std::vector<Vec3> out(static_cast<std::size_t>(v.size() / 3));
  for (std::size_t p = 0; p < out.size(); ++p) {
    for (int a = 0; a < 3; ++a) out[p][a] = v(3 * static_cast<Eigen::Index>(p) + a);
  }
  return out;
}

}  // namespace deli
