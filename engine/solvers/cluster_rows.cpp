#include "solvers/cluster_rows.hpp"

#include <cstdlib>

namespace deli {

ClusterRows::ClusterRows(const LocalCluster& cluster)
    : cluster_(cluster), rows_(cluster.rows.size()), touches_(cluster.size()) {
  for (std::size_t k = 0; k < rows_; ++k) {
    const Constraint& c = cluster.rows[k];
    touches_[c.i].push_back({static_cast<int>(k), 1.0});
    if (c.j >= 0) touches_[c.j].push_back({static_cast<int>(k), -1.0});
  }
  for (const std::vector<Touch>& t : touches_) {
    if (t.size() > 2 || (t.size() == 2 && std::abs(t[1].row - t[0].row) != 1)) tridiagonal_ = false;
  }
}

void ClusterRows::coupling_bands(const std::vector<Vec3>& a, const std::vector<Vec3>& b,
                                 Tridiagonal& out) const {
  out.resize_zero(static_cast<Eigen::Index>(rows_));
  for (std::size_t p = 0; p < touches_.size(); ++p) {
    const double w = cluster_.inverse_mass[p];
    for (const Touch& k : touches_[p]) {
      for (const Touch& l : touches_[p]) {
        const double term = k.sign * l.sign * w * dot(a[k.row], b[l.row]);
        if (l.row == k.row) {
          out.diagonal(k.row) += term;
        } else if (l.row == k.row + 1) {
          out.upper(k.row) += term;
        } else {
          out.lower(k.row) += term;
        }
      }
    }
  }
}

std::vector<Vec3> ClusterRows::directions(const std::vector<Vec3>& x, const Box& box) const {
  std::vector<Vec3> u(rows_);
  for (std::size_t k = 0; k < rows_; ++k) u[k] = evaluate(cluster_.rows[k], x.data(), box).u;
  return u;
}

Eigen::MatrixXd ClusterRows::coupling(const std::vector<Vec3>& a,
                                      const std::vector<Vec3>& b) const {
  const auto m = static_cast<Eigen::Index>(rows_);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, m);
  for (std::size_t p = 0; p < touches_.size(); ++p) {
    const double w = cluster_.inverse_mass[p];
    for (const Touch& k : touches_[p]) {
      for (const Touch& l : touches_[p]) {
        A(k.row, l.row) += k.sign * l.sign * w * dot(a[k.row], b[l.row]);
      }
    }
  }
  return A;
}

std::vector<Vec3> ClusterRows::impulse(const std::vector<Vec3>& u, const Eigen::VectorXd& z) const {
  std::vector<Vec3> out;
  impulse_into(u, z, out);
  return out;
}

void ClusterRows::impulse_into(const std::vector<Vec3>& u, const Eigen::VectorXd& z,
                               std::vector<Vec3>& out) const {
  out.assign(touches_.size(), Vec3{});
  for (std::size_t p = 0; p < touches_.size(); ++p) {
    for (const Touch& k : touches_[p]) out[p] += u[k.row] * (k.sign * z(k.row));
  }
}

Eigen::VectorXd ClusterRows::project(const std::vector<Vec3>& u, const std::vector<Vec3>& v) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows_));
  for (std::size_t p = 0; p < touches_.size(); ++p) {
    for (const Touch& k : touches_[p]) out(k.row) += k.sign * dot(u[k.row], v[p]);
  }
  return out;
}

}  // namespace deli
