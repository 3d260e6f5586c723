#pragma once

#include <Eigen/Dense>
#include <memory>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/solver_status.hpp"

namespace deli {

// Scratch space of the rod-chain kernels, kept by the caller from solve to solve (no
// allocation once it has grown to the longest chain). Eigen vectors where the generic
// solvers use Eigen reductions, so that those reductions see the same alignment and sum in
// the same order.
struct RodChainWorkspace {
  std::vector<Vec3> q, x0, x, ux, xt, uxt, v;
  std::vector<double> rx, rxt;
  Eigen::VectorXd z, step, trial, phi, pt, pivots;
};

// A cluster of rods only, numbered along a linear chain (consecutive rows share exactly
// one particle, other rows none): the molecules of a chain melt. Its position update
// (SHAKE as a tridiagonal Newton with a line search) and momentum projection (RATTLE's
// velocity step) run here on flat arrays, with each rod's direction and length computed
// once per position instead of through the generic row evaluation, and without gathering
// into per-cluster containers. Every number is computed by the same operations in the same
// order as the generic solvers (solve_position_update, project_momentum over ClusterRows):
// the results agree bit for bit. When a pivot vanishes (where the generic solvers switch to
// a dense solve) or the Newton iteration does not converge (or its line search finds no descent),
// the kernels return false and the caller takes the generic path, which redoes the solve and
// reports a failure.
class RodChain {
 public:
  // The chain form of a cluster, or null when its rows are not such a chain.
  static std::unique_ptr<RodChain> make(const LocalCluster& cluster);

  std::size_t rows() const { return length_.size(); }

  // Position update: x = x0 + h M^-1 C(q) z with every rod held (|f(x)| <= tolerance), for
  // x0 = q + delta. Positions and displacements indexed globally; adds the impulses C(q) z
  // into `impulse` (global, entries of the chain's particles overwritten) and
  // sum z_k |q_i - q_j| to `virial`. Returns false (nothing written) when the generic path
  // must take over.
  [[nodiscard]] bool solve_positions(const Vec3* q, const Vec3* delta, double h, const Box& box,
                                     double tolerance, int max_iterations, int line_search_limit,
                                     RodChainWorkspace& ws, Vec3* impulse, double& virial,
                                     SolverStatus& status) const;

  // Momentum projection at positions x: p <- p + C(x) mu with C(x)^T M^-1 p = 0; writes
  // rod k's virial term mu_k |x_i - x_j| to virial_terms[k], k < rows() (the caller adds
  // them in row order). Returns false (p untouched) when the generic path must take over.
  [[nodiscard]] bool project_momenta(const Vec3* x, Vec3* p, const Box& box, RodChainWorkspace& ws,
                                     double* virial_terms) const;

  // max_k |r_k - L_k| / L_k over the rods at positions x (indexed globally), at least
  // `start`: the number a loop over the rows with gap_of would give, bit for bit. The lengths
  // are those last computed at these positions (the momentum projection's, at the end of a
  // step) when x is bit for bit where they were computed, else computed.
  double largest_relative_deviation(const Vec3* x, const Box& box, RodChainWorkspace& ws,
                                    double start) const;

 private:
  RodChain() = default;
  // Directions and lengths of every rod at local positions x.
  void directions(const std::vector<Vec3>& x, const Box& box, std::vector<Vec3>& u,
                  std::vector<double>& r) const;
  // The two halves of directions(): the rods' minimum-image differences d and squared
  // lengths d2, then d, d2 turned into directions and lengths in place.
  void differences(const std::vector<Vec3>& x, const Box& box, std::vector<Vec3>& d,
                   std::vector<double>& d2) const;
  void normalize(std::vector<Vec3>& u, std::vector<double>& r) const;
  // An upper bound, from the squared lengths d2 alone (no square roots), on max_k |r_k - L_k|
  // as directions() and the residual would compute it; +inf when that bound exceeds
  // `tolerance` for some rod (or d2 is not finite).
  double held_bound(const std::vector<double>& d2, double tolerance) const;
  // Per particle: sum over its rods of s u z (the impulse C z).
  Vec3 impulse_on(std::size_t p, const std::vector<Vec3>& u, const Eigen::VectorXd& z) const {
    Vec3 out{};
    out += u[first_row_[p]] * (first_sign_[p] * z(first_row_[p]));
    if (second_row_[p] >= 0) out += u[second_row_[p]] * (second_sign_[p] * z(second_row_[p]));
    return out;
  }
  // Solves (scale A) x = -minus_rhs for the Newton (and RATTLE) matrix
  // A = sum_p w_p s_k s_l a_k . b_l, tridiagonal, its band entries made as the elimination
  // reaches them. False when a pivot vanishes or x is not finite (the generic path takes over).
  [[nodiscard]] bool solve_coupled(const std::vector<Vec3>& a, const std::vector<Vec3>& b,
                                   double scale, const Eigen::VectorXd& minus_rhs,
                                   Eigen::VectorXd& x, Eigen::VectorXd& c) const;
  // Directions and lengths at the start of the step's positions q, in memo_: those of the
  // last momentum projection (or solve) when q is bit for bit the positions it had, as it is
  // unless the neighbour list wrapped them in between; computed otherwise.
  void start_directions(const std::vector<Vec3>& q, const Box& box) const;
  // Computes the directions and lengths at local positions x into memo_.
  void remember_directions(const std::vector<Vec3>& x, const Box& box) const;
  // Whether the memo holds the directions at local positions x in this box.
  bool remembered_at(const std::vector<Vec3>& x, const Box& box) const;

  // The last directions computed at a step's end or start positions, with those positions
  // (local) and the box's periods: directions() is a function of these alone. Mutable: a
  // cache, invisible in the results (a chain is solved by one thread at a time; threads
  // solve different chains).
  struct DirectionsMemo {
    bool valid = false;
    std::vector<Vec3> x, u;
    std::vector<double> r;
    Vec3 period, inverse_period;
  };
  mutable DirectionsMemo memo_;
  // Per rod: the periodic image (in periods, per axis) its last minimum image subtracted,
  // tried first by differences(). Mutable like memo_: a cache that never changes a number.
  mutable std::vector<Vec3> image_;

  std::vector<std::int32_t> particles_;  // local -> global
  std::vector<double> inverse_mass_;
  // Per rod: particles i (+u) and j (-u), length; the lower and higher numbered of the two
  // with their signs (sums over particles run in particle order); the particle shared with
  // the next rod and the product of its signs in the two rods.
  std::vector<std::int32_t> i_, j_, low_, high_, shared_;
  std::vector<double> length_, inverse_length_, low_sign_, high_sign_, shared_sign_;
  // Per particle: its rods in row order with their signs (second_row_ -1: none).
  std::vector<std::int32_t> first_row_, second_row_;
  std::vector<double> first_sign_, second_sign_;
};

}  // namespace deli
