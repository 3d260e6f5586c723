#pragma once

#include <Eigen/Dense>
#include <vector>

#include "constraints/clusters.hpp"
#include "constraints/constraint_set.hpp"
#include "forces/force_term.hpp"

namespace deli {

enum class ReflectionOperator { generalized, moreau };
enum class ReflectionEnergy { hamiltonian, shadow };

// Verlet's second-order shadow Hamiltonian restricted to one cluster:
// H~ = H - h^2/24 dV^T M^-1 dV + h^2/12 v^T d2V v, quadratic in p with
// K = M^-1/2 + h^2/12 M^-1 d2V M^-1. `pairs` (pair_count of them) are the pair Hessian
// blocks touching the cluster in local indices (b = -1: the particle `outside` the cluster,
// whose velocity is its momentum in `momenta` over its mass), each pointing to its block
// (among the gathered blocks of every reflected cluster). All referred to, not copied: the
// outside particles' momenta are read while the cluster is reflected, which changes only its
// own.
struct ShadowOperator {
  struct LocalPair {
    std::int32_t a, b;
    std::int32_t outside;  // the particle outside the cluster where b = -1, else -1
    const PairHessian* block;
  };
  double h = 0;
  const LocalPair* pairs = nullptr;
  std::size_t pair_count = 0;
  const Vec3* momenta = nullptr;
  const double* mass = nullptr;
  // d2V v over the cluster's coordinates (3n); outside particles move with their own
  // velocities when `with_outside`, else stand still.
  Eigen::VectorXd hessian_times(const Eigen::VectorXd& v, bool with_outside) const;
};

struct ReflectionStats {
  int iterations = 0;   // solves (Algorithm 2 loops; 1 for Moreau)
  int reflected = 0;    // rows that received an impulse
  bool capped = false;  // Algorithm 2 hit its iteration cap or stalled
  bool cycled = false;  // Algorithm 2 returned to momenta it had already produced
  // Algorithm 2 ended with no row approaching: reflected again, the cluster would not change.
  bool settled = false;
  int shadow_fallbacks = 0;  // solves where the shadow energy had no reflection: H used
  int qp_caps = 0;           // QP solves that hit their iteration cap (see reflect())
  // The impulse each local row applied, along its own gradient (equality rows carry the
  // share of the projected normals that runs along them): for the constraint virial.
  std::vector<double> row_impulse;
};

// The cluster's inequality normals at x projected onto the cotangent space of its equality
// rows (columns in the order of the inequality rows), in the 3n local coordinates.
Eigen::MatrixXd projected_normals(const LocalCluster& cluster, const std::vector<bool>& equality,
                                  const std::vector<Vec3>& x, const Box& box);

// Energy-preserving reflection of the momenta p of one cluster off its inequality rows
// at q (the paper's Algorithms 2 and 3, energy E = H, K = M^-1 / 2). Inequality normals
// are projected onto the cotangent space of the cluster's equality rows (rods, strings),
// so the momenta stay tangent to the rod manifold. Each solve minimises
// |L^T (N lambda + 2 p)| over lambda >= 0 (K = L L^T), whose optimality conditions give
// lambda^T N^T K (N lambda + 2 p) = 0: E conserved exactly whatever the number of rows.
// Rows with normal velocity below -tolerance count as approaching. Algorithm 2 always ends:
// at `limits.reflection_solves`, when a solve stalls (approaching, no energy-preserving impulse) or
// when it cycles (momenta repeat bit for bit), the rows met so far get an inelastic
// projection instead and the event is flagged in the stats.
// With `shadow`, E is Verlet's shadow Hamiltonian; a solve where it admits no reflection
// (an approaching row with grad g^T K p >= 0, or K not positive on the normals) falls back
// to E = H for that solve and is counted.
// A QP solve that ends at its iteration cap (`limits.qp_iterations`; not optimal, so not
// energy-preserving) is counted in qp_caps and handled as the nearest safe case: a shadow solve
// falls back to H, an H solve stops Algorithm 2 as a stall (inelastic projection), and a capped
// inelastic projection applies its feasible, non-optimal impulses (the feasibility guard of the
// position update keeps the step from ending overlapped).
[[nodiscard]] ReflectionStats reflect(const LocalCluster& cluster,
                                      const std::vector<bool>& equality, const std::vector<Vec3>& q,
                                      std::vector<Vec3>& p, const Box& box, ReflectionOperator op,
                                      double tolerance, const SolverLimits& limits,
                                      const ShadowOperator* shadow = nullptr);

}  // namespace deli
