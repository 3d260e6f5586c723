#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"

namespace deli {

// Dense per-cluster linear algebra: clusters are small (a chain's rods, a few contacts),
// so gradients are held as a 3n x m matrix.

// Gradient columns of the selected rows at positions x (minimum image through `box`).
Eigen::MatrixXd gradient_matrix(const LocalCluster& cluster, const std::vector<int>& rows,
                                const std::vector<Vec3>& x, const Box& box);
// Diagonal of M^-1 over the 3n coordinates.
Eigen::VectorXd inverse_mass_diagonal(const LocalCluster& cluster);

Eigen::VectorXd flatten(const std::vector<Vec3>& v);
std::vector<Vec3> unflatten(const Eigen::VectorXd& v);

// The same into kept storage (no allocation when the size is the one it already has).
void gradient_matrix(const LocalCluster& cluster, const std::vector<int>& rows,
                     const std::vector<Vec3>& x, const Box& box, Eigen::MatrixXd& G);
void inverse_mass_diagonal(const LocalCluster& cluster, Eigen::VectorXd& w);
void flatten(const std::vector<Vec3>& v, Eigen::VectorXd& out);
void unflatten(const Eigen::VectorXd& v, std::vector<Vec3>& out);

}  // namespace deli
