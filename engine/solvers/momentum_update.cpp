#include "solvers/momentum_update.hpp"

#include "solvers/cluster_matrices.hpp"

namespace deli {

SolverStatus project_momentum(const LocalCluster& cluster, const std::vector<int>& rows,
                              const std::vector<Vec3>& x, std::vector<Vec3>& p, const Box& box,
                              Eigen::VectorXd& mu) {
  SolverStatus status;
  status.iterations = 1;
  if (rows.empty()) {
    status.converged = true;
    mu.resize(0);
    return status;
  }
  const Eigen::MatrixXd C = gradient_matrix(cluster, rows, x, box);
  const Eigen::VectorXd w = inverse_mass_diagonal(cluster);
  Eigen::VectorXd flat = flatten(p);
  const Eigen::MatrixXd WC = w.asDiagonal() * C;
  const Eigen::MatrixXd A = C.transpose() * WC;
  const Eigen::VectorXd b = -(WC.transpose() * flat);
  Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
  mu = ldlt.solve(b);
  if (ldlt.info() != Eigen::Success || !mu.allFinite()) {
    mu = A.completeOrthogonalDecomposition().solve(b);  // dependent rows (a rigid loop)
  }
  flat += C * mu;
  p = unflatten(flat);
  status.residual = (WC.transpose() * flat).lpNorm<Eigen::Infinity>();
  status.converged = mu.allFinite();
  return status;
}

}  // namespace deli
