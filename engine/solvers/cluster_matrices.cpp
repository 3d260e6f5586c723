#include "solvers/cluster_matrices.hpp"

namespace deli {

void gradient_matrix(const LocalCluster& cluster, const std::vector<int>& rows,
                     const std::vector<Vec3>& x, const Box& box, Eigen::MatrixXd& G) {
  const auto n = static_cast<Eigen::Index>(cluster.size());
  G.setZero(3 * n, static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Constraint& c = cluster.rows[rows[k]];
    const Vec3 u = evaluate(c, x.data(), box).u;
    const auto col = static_cast<Eigen::Index>(k);
    for (int a = 0; a < 3; ++a) {
      G(3 * c.i + a, col) += u[a];
      if (c.j >= 0) G(3 * c.j + a, col) -= u[a];
    }
  }
}

Eigen::MatrixXd gradient_matrix(const LocalCluster& cluster, const std::vector<int>& rows,
                                const std::vector<Vec3>& x, const Box& box) {
  Eigen::MatrixXd G;
  gradient_matrix(cluster, rows, x, box, G);
  return G;
}

void inverse_mass_diagonal(const LocalCluster& cluster, Eigen::VectorXd& w) {
  w.resize(3 * static_cast<Eigen::Index>(cluster.size()));
  for (std::size_t p = 0; p < cluster.size(); ++p) {
    for (int a = 0; a < 3; ++a) w(3 * static_cast<Eigen::Index>(p) + a) = cluster.inverse_mass[p];
  }
}

Eigen::VectorXd inverse_mass_diagonal(const LocalCluster& cluster) {
  Eigen::VectorXd w;
  inverse_mass_diagonal(cluster, w);
  return w;
}

void flatten(const std::vector<Vec3>& v, Eigen::VectorXd& out) {
  out.resize(3 * static_cast<Eigen::Index>(v.size()));
  for (std::size_t p = 0; p < v.size(); ++p) {
    for (int a = 0; a < 3; ++a) out(3 * static_cast<Eigen::Index>(p) + a) = v[p][a];
  }
}

Eigen::VectorXd flatten(const std::vector<Vec3>& v) {
  Eigen::VectorXd out;
  flatten(v, out);
  return out;
}

void unflatten(const Eigen::VectorXd& v, std::vector<Vec3>& out) {
  out.resize(static_cast<std::size_t>(v.size() / 3));
  for (std::size_t p = 0; p < out.size(); ++p) {
    for (int a = 0; a < 3; ++a) out[p][a] = v(3 * static_cast<Eigen::Index>(p) + a);
  }
}

std::vector<Vec3> unflatten(const Eigen::VectorXd& v) {
  std::vector<Vec3> out;
  unflatten(v, out);
  return out;
}

}  // namespace deli
