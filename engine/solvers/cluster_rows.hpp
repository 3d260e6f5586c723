#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/tridiagonal.hpp"

namespace deli {

// The sparse structure of a cluster's rows: each row touches one or two particles with
// sign +1 (i) or -1 (j), and each particle a few rows. Products of gradient matrices are
// built entry by entry over shared particles: O(rows) work for a chain instead of the
// O(n m^2) of dense 3n x m products.
class ClusterRows {
 public:
  explicit ClusterRows(const LocalCluster& cluster);

  std::size_t rows() const { return rows_; }
  const LocalCluster& cluster() const { return cluster_; }
  // Whether rows couple only to their neighbours in the row order (every particle touched
  // by at most two rows, numbered consecutively): a linear chain's rods in chain order.
  // Then coupling() is tridiagonal and coupling_bands() gives it in O(rows).
  bool tridiagonal() const { return tridiagonal_; }
  // Gradient directions u of every row at positions x.
  std::vector<Vec3> directions(const std::vector<Vec3>& x, const Box& box) const;
  // A_kl = sum over particles p shared by rows k, l of s_k s_l w_p a_k . b_l, for row
  // directions a (rows k) and b (rows l); w_p the inverse masses.
  Eigen::MatrixXd coupling(const std::vector<Vec3>& a, const std::vector<Vec3>& b) const;
  // The same matrix in band form (only when tridiagonal()); every entry is summed in the
  // same order as coupling()'s, so the entries agree bit for bit.
  void coupling_bands(const std::vector<Vec3>& a, const std::vector<Vec3>& b,
                      Tridiagonal& out) const;
  // Per particle: sum over its rows of s_k u_k z_k (the impulse C z).
  std::vector<Vec3> impulse(const std::vector<Vec3>& u, const Eigen::VectorXd& z) const;
  // The same into `out` (one entry per particle), without allocating.
  void impulse_into(const std::vector<Vec3>& u, const Eigen::VectorXd& z,
                    std::vector<Vec3>& out) const;
  // Per row: s_i u . v_i + s_j u . v_j (C^T v) for per-particle vectors v.
  Eigen::VectorXd project(const std::vector<Vec3>& u, const std::vector<Vec3>& v) const;

 private:
  const LocalCluster& cluster_;
  std::size_t rows_;
  struct Touch {
    int row;
    double sign;
  };
  std::vector<std::vector<Touch>> touches_;  // per particle
  bool tridiagonal_ = true;
};

}  // namespace deli
