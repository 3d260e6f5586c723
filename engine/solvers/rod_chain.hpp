#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <memory>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/solver_status.hpp"

namespace deli {

// Scratch space of the rod-chain kernels, kept by the caller from solve to solve (no
// allocation once it has grown to the longest chain). Beads and rods in chain order as
// structures of arrays (rod_chain_passes.hpp); Eigen vectors where the generic solvers use
// Eigen reductions, so that those reductions see the same alignment and sum in the same
// order.
struct RodChainWorkspace {
  std::vector<double> q, x0, x, xt, v, impulse, hw;                           // per bead
  std::vector<double> ux, uxt, rx, rxt, bounds, lower, diagonal, upper, rhs;  // per rod
  std::vector<std::uint8_t> usable;
  Eigen::VectorXd z, step, trial, phi, pt, pivots;
};

// Scratch space of the lockstep kernels (RodChain::solve_positions_lanes and
// project_momenta_lanes): one workspace per lane, and the lanes' band entries interleaved.
struct RodChainLanes {
  static constexpr std::size_t width = 8;  // rod_passes::lanes
  RodChainWorkspace lane[width];
  std::vector<double> lower, diagonal, upper, rhs, x, c, virial_terms;
  std::uint8_t solved[width];
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

  // solve_positions for chains[0..count) at once (count <= RodChainLanes::width, every
  // chain with the same number of rods), their eliminations run with one chain per vector
  // lane; every lane's numbers are solve_positions' own. solved[l]: whether chain l's
  // results were written (impulse, virial[l], status[l]). A chain that needs a line-search
  // halving, more iterations than allowed or the generic path is left unsolved: the
  // caller solves it alone with solve_positions (which redoes it from the start).
  static void solve_positions_lanes(const RodChain* const* chains, std::size_t count, const Vec3* q,
                                    const Vec3* delta, double h, const Box& box, double tolerance,
                                    int max_iterations, RodChainLanes& lanes, Vec3* impulse,
                                    double* virial, SolverStatus* status, bool* solved);
  // project_momenta for chains[0..count) at once, likewise; chain l's virial terms go to
  // lanes.virial_terms[l * rows() ...]. An unsolved chain's p is untouched: the caller
  // projects it alone with project_momenta.
  static void project_momenta_lanes(const RodChain* const* chains, std::size_t count, const Vec3* x,
                                    Vec3* p, const Box& box, RodChainLanes& lanes, bool* solved);

  // max_k |r_k - L_k| / L_k over the rods at positions x (indexed globally), at least
  // `start`: the number a loop over the rows with gap_of would give, bit for bit. The lengths
  // are those last computed at these positions (the momentum projection's, at the end of a
  // step) when x is bit for bit where they were computed, else computed.
  double largest_relative_deviation(const Vec3* x, const Box& box, RodChainWorkspace& ws,
                                    double start) const;

 private:
  RodChain() = default;
  std::size_t beads() const { return bead_particle_.size(); }
  // Positions (or another per-particle vector, times a factor per bead) gathered into chain
  // order as a structure of arrays.
  void gather(const Vec3* global, std::vector<double>& out) const;
  // Directions and lengths of every rod at positions x (chain order).
  void directions(const double* x, const Box& box, double* u, double* r) const;
  // The rods' minimum-image differences d and squared lengths d2 at positions x (the first
  // half of directions(); rod_passes::normalize is the second).
  void differences(const double* x, const Box& box, double* d, double* d2) const;
  // An upper bound, from the squared lengths d2 alone (no square roots), on max_k |r_k - L_k|
  // as directions() and the residual would compute it; +inf when that bound exceeds
  // `tolerance` for some rod (or d2 is not finite).
  double held_bound(const double* d2, double tolerance, RodChainWorkspace& ws) const;
  // The phases of solve_positions. Gathers the step's start and free positions, the start
  // directions, and the residual at the free positions: true when the rods are held there.
  bool begin_positions(const Vec3* q, const Vec3* delta, double h, const Box& box, double tolerance,
                       RodChainWorkspace& ws, SolverStatus& status) const;
  // Whether the rods at x, whose differences and squared lengths u, r hold, are proven held
  // (with the residual's norm below `merit_cap` too) without their square roots; otherwise
  // u, r, phi become the directions, lengths and residual at x.
  bool held_or_residual(Eigen::VectorXd& phi, std::vector<double>& u, std::vector<double>& r,
                        double merit_cap, double tolerance, RodChainWorkspace& ws,
                        SolverStatus& status) const;
  // After the Newton step ws.step: the line search (at most `halvings` halvings).
  enum class LineSearch { held, descended, failed };
  LineSearch line_search(const Box& box, double tolerance, int halvings, RodChainWorkspace& ws,
                         SolverStatus& status) const;
  // Per bead, the impulse C z of the multipliers ws.z along the remembered directions, into
  // ws.impulse (x, y, z blocks of beads() each).
  void bead_impulses(RodChainWorkspace& ws) const;
  // The impulses C(q) z and the virial of a converged solve.
  void finish_positions(RodChainWorkspace& ws, Vec3* impulse, double& virial) const;
  // Gathers the velocities at positions x, remembers x's directions and makes RATTLE's
  // right-hand side in ws.pt.
  void begin_momenta(const Vec3* x, const Vec3* p, const Box& box, RodChainWorkspace& ws) const;
  // Adds the impulses C(x) mu (mu in ws.z) to p and writes the virial terms.
  void finish_momenta(RodChainWorkspace& ws, Vec3* p, double* virial_terms) const;
  // The lanes' band entries, interleaved (rod_passes::eliminate_lanes), solved; the
  // solutions into each solving lane's ws.step (or ws.z). lanes.solved[l]: whether lane l's
  // elimination succeeded.
  static void solve_lanes(std::size_t rows, const bool* solving, RodChainLanes& lanes, bool into_z);
  // The band entries and right-hand side solve_coupled eliminates, into ws.
  void make_bands(const double* a, const double* b, double scale, const Eigen::VectorXd& minus_rhs,
                  RodChainWorkspace& ws) const;
  // Solves (scale A) x = -minus_rhs for the Newton (and RATTLE) matrix
  // A = sum_p w_p s_k s_l a_k . b_l, tridiagonal (a, b: directions in chain order). False
  // when a pivot vanishes or x is not finite (the generic path takes over).
  [[nodiscard]] bool solve_coupled(const double* a, const double* b, double scale,
                                   const Eigen::VectorXd& minus_rhs, Eigen::VectorXd& x,
                                   RodChainWorkspace& ws) const;
  // Directions and lengths at the start of the step's positions q, in memo_: those of the
  // last momentum projection (or solve) when q is bit for bit the positions it had, as it is
  // unless the neighbour list wrapped them in between; computed otherwise.
  void start_directions(const std::vector<double>& q, const Box& box) const;
  // Computes the directions and lengths at positions x into memo_.
  void remember_directions(const std::vector<double>& x, const Box& box) const;
  // Whether the memo holds the directions at positions x in this box.
  bool remembered_at(const std::vector<double>& x, const Box& box) const;

  // The last directions computed at a step's end or start positions, with those positions
  // and the box's periods (chain order): directions() is a function of these alone.
  // Mutable: a cache, invisible in the results (a chain is solved by one thread at a time;
  // threads solve different chains).
  struct DirectionsMemo {
    bool valid = false;
    std::vector<double> x, u, r;
    Vec3 period, inverse_period;
  };
  mutable DirectionsMemo memo_;
  // Per rod and axis: the periodic image (in periods) its last minimum image subtracted,
  // tried first by differences(). Mutable like memo_: a cache that never changes a number.
  mutable std::vector<double> image_;

  // Per bead (chain order: rod k joins beads k and k+1): its particle (global index), inverse
  // mass, and the signs of its rods in row order (second_sign_ 0 at the ends).
  std::vector<std::int32_t> bead_particle_;
  std::vector<double> bead_inverse_mass_, first_sign_, second_sign_;
  // Per rod: whether its particle i is bead k (else bead k+1), whether its lower numbered
  // particle is bead k (sums over a rod's particles run in particle order); its length and
  // inverse; the signs and inverse masses of its lower and higher numbered particles; the
  // sign product times inverse mass of the bead it shares with the next rod.
  std::vector<double> forward_, low_first_;  // 1 or 0
  std::vector<double> length_, inverse_length_, low_sign_, high_sign_, w_low_, w_high_, coupling_;
};

}  // namespace deli
