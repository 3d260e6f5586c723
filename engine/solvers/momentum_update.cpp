#include "solvers/momentum_update.hpp"

#include "solvers/cluster_rows.hpp"
#include "solvers/least_norm.hpp"

namespace deli {

SolverStatus project_momentum(const LocalCluster& cluster, const std::vector<int>& rows,
                              const std::vector<Vec3>& x, std::vector<Vec3>& p, const Box& box,
                              double tolerance, Eigen::VectorXd& mu) {
  if (rows.empty()) {
    SolverStatus status;
    status.iterations = 1;
    status.converged = true;
    mu.resize(0);
    return status;
  }
  // The selected rows as a cluster of their own (same particles).
  LocalCluster selected = cluster;
  selected.rows.clear();
  for (int r : rows) selected.rows.push_back(cluster.rows[r]);
  return project_momentum(ClusterRows(selected), x, p, box, tolerance, mu);
}

SolverStatus project_momentum(const ClusterRows& structure, const std::vector<Vec3>& x,
                              std::vector<Vec3>& p, const Box& box, double tolerance,
                              Eigen::VectorXd& mu) {
  SolverStatus status;
  status.iterations = 1;
  const LocalCluster& cluster = structure.cluster();
  const std::vector<Vec3> u = structure.directions(x, box);
  std::vector<Vec3> v(p.size());
  for (std::size_t k = 0; k < p.size(); ++k) v[k] = p[k] * cluster.inverse_mass[k];
  // (C^T M^-1 C) mu = -C^T M^-1 p.
  const Eigen::VectorXd b = -structure.project(u, v);
  bool solved = false;
  if (structure.tridiagonal()) {
    Tridiagonal bands;
    structure.coupling_bands(u, u, bands);
    solved = solve_tridiagonal(bands, b, mu);
  }
  if (!solved) {
    const Eigen::MatrixXd A = structure.coupling(u, u);
    Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
    mu = ldlt.solve(b);
    // Dependent rows (a rigid loop, a contact repeating a rod) make A singular: LDLT then
    // fails, or gives multipliers that do not solve the system; least norm instead.
    if (ldlt.info() != Eigen::Success || !mu.allFinite() ||
        !(residual_norm(A * mu - b) <= tolerance)) {
      mu = least_norm_solve(A, b);
    }
  }
  const std::vector<Vec3> j = structure.impulse(u, mu);
  for (std::size_t k = 0; k < p.size(); ++k) {
    p[k] += j[k];
    v[k] = p[k] * cluster.inverse_mass[k];
  }
  status.residual = residual_norm(structure.project(u, v));
  status.converged = status.residual <= tolerance;
  return status;
}

}  // namespace deli
