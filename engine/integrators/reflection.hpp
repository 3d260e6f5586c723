#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"

namespace deli {

enum class ReflectionOperator { generalized, moreau };

struct ReflectionStats {
  int iterations = 0;   // solves (Algorithm 2 loops; 1 for Moreau)
  int reflected = 0;    // rows that received an impulse
  bool capped = false;  // Algorithm 2 hit its iteration cap or stalled
};

// Energy-preserving reflection of the momenta p of one cluster off its inequality rows
// at q (the paper's Algorithms 2 and 3, energy E = H, K = M^-1 / 2). Inequality normals
// are projected onto the cotangent space of the cluster's equality rows (rods, strings),
// so the momenta stay tangent to the rod manifold. Each solve minimises
// |L^T (N lambda + 2 p)| over lambda >= 0 (K = L L^T), whose optimality conditions give
// lambda^T N^T K (N lambda + 2 p) = 0: E conserved exactly whatever the number of rows.
// Rows with normal velocity below -tolerance count as approaching.
// The cluster's inequality normals at x projected onto the cotangent space of its equality
// rows (columns in the order of the inequality rows), in the 3n local coordinates.
Eigen::MatrixXd projected_normals(const LocalCluster& cluster, const std::vector<bool>& equality,
                                  const std::vector<Vec3>& x, const Box& box);

ReflectionStats reflect(const LocalCluster& cluster, const std::vector<bool>& equality,
                        const std::vector<Vec3>& q, std::vector<Vec3>& p, const Box& box,
                        ReflectionOperator op, double tolerance, int max_iterations = 100);

}  // namespace deli
