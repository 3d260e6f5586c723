#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/cluster_rows.hpp"
#include "solvers/solver_status.hpp"

namespace deli {

// GVI's position update on one cluster: find multipliers z (impulses) with
//   x = x0 + h M^-1 C(q) z,   f(x) = 0 (equality rows),   0 <= z_k _|_ g_k(x) >= 0 (the rest),
// x0 being the unconstrained step. With only equality rows this is SHAKE's position step.
// Semismooth Newton on the Fischer-Burmeister reformulation, with a backtracking line
// search on the squared residual; converged when every equality residual and every
// complementarity residual is below `tolerance` (sigma). At most `newton_limit` Newton
// steps; a step whose line search finds no decrease of the residual in `line_search_limit`
// halvings ends the solve (not converged: an uphill step is never taken).
struct PositionUpdate {
  std::vector<Vec3> x;
  // C(q) z per particle: the constraint impulse. x - x0 = h M^-1 impulse; the momentum
  // update adds the impulse itself rather than recovering it from positions, which would
  // lose digits to cancellation and bias the momenta by rounding at every step.
  std::vector<Vec3> impulse;
  Eigen::VectorXd z;
  SolverStatus status;
  bool line_search_failed = false;  // why it ended unconverged, when it did
};
[[nodiscard]] PositionUpdate solve_position_update(const LocalCluster& cluster,
                                                   const std::vector<bool>& equality,
                                                   const std::vector<Vec3>& q,
                                                   const std::vector<Vec3>& x0, double h,
                                                   const Box& box, double tolerance,
                                                   int newton_limit, int line_search_limit);
// The same with the cluster's row structure prepared by the caller (reused across steps).
// Rods only, numbered along a linear chain (structure.tridiagonal()): each Newton step is an
// O(rows) tridiagonal solve instead of a dense LU (results differ from the dense solve only
// by rounding; the residual tolerance is the same).
[[nodiscard]] PositionUpdate solve_position_update(const ClusterRows& structure,
                                                   const std::vector<bool>& equality,
                                                   const std::vector<Vec3>& q,
                                                   const std::vector<Vec3>& x0, double h,
                                                   const Box& box, double tolerance,
                                                   int newton_limit, int line_search_limit);

}  // namespace deli
