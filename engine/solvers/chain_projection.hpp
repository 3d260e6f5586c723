#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"
#include "system/box.hpp"

namespace deli {

// N <- N - F Y with Y = (F^T W F)^-1 F^T W N: the columns of N (inequality normals, one
// per column, 3 entries per particle) made W-orthogonal to the gradients F of the cluster's
// equality rows `equality_rows` at x (W = M^-1 diagonal). When those rows are pair rows
// that form chains (each particle in at most two rows, and then in consecutive ones, as a
// linear chain's rods numbered along it), F^T W F is tridiagonal: built from the rods'
// directions and solved by elimination without pivoting in O(rows) instead of a dense product and
// decomposition. Returns false, leaving N and Y untouched, for rows that do not form
// chains or a pivot that vanishes (dependent rows): the caller then takes the dense
// pseudo-inverse.
[[nodiscard]] bool project_out_chains(const LocalCluster& cluster,
                                      const std::vector<int>& equality_rows,
                                      const std::vector<Vec3>& x, const Box& box,
                                      Eigen::MatrixXd& N, Eigen::MatrixXd& Y);

}  // namespace deli
