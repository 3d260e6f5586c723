#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/cluster_rows.hpp"
#include "solvers/solver_status.hpp"

namespace deli {

// GVI's momentum update on one cluster (RATTLE's velocity step plus the smooth contacts):
// p <- p + C(x) mu with C(x)^T M^-1 p = 0 for the selected rows; one symmetric positive
// (semi)definite solve, least norm where the rows are dependent (a rigid loop). Converged
// when the residual max |C^T M^-1 p| after the update is at most `tolerance` (a normal
// velocity, sigma/tau); `mu` receives the multipliers.
SolverStatus project_momentum(const LocalCluster& cluster, const std::vector<int>& rows,
                              const std::vector<Vec3>& x, std::vector<Vec3>& p, const Box& box,
                              double tolerance, Eigen::VectorXd& mu);
// The same over every row of a prepared structure; a linear chain's rods (tridiagonal())
// take an O(rows) solve instead of a dense LDLT (equal up to rounding).
SolverStatus project_momentum(const ClusterRows& structure, const std::vector<Vec3>& x,
                              std::vector<Vec3>& p, const Box& box, double tolerance,
                              Eigen::VectorXd& mu);

}  // namespace deli
