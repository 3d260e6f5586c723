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
  // residual_norm of phi and pt, made with them; phi's squared norm once known (else < 0).
  double phi_norm = 0.0, pt_norm = 0.0, merit = -1.0;
};

class RodChain;

// Scratch space of the lockstep kernels (RodChain::solve_positions_lanes and
// project_momenta_lanes): one workspace per lane, and the lanes' band entries interleaved.
struct RodChainLanes {
  static constexpr std::size_t width = 8;  // rod_passes::lanes
  RodChainWorkspace lane[width];
  // A group of chains side by side (rod_passes::across layout): their constants, with the
  // step h, and their periodic images (a cache that never changes a number, as RodChain's own).
  struct Group {
    const RodChain* chains[width] = {};
    std::size_t rows = 0;
    double h = 0.0;
    std::vector<double> forward, length, inverse_length, w_low, w_high, coupling, low_first,
        low_sign, high_sign, image;                                 // rods
    std::vector<double> first_sign, second_sign, hw, inverse_mass;  // beads
    std::vector<std::int32_t> particle;                             // beads
    // Lane l's bead b is particle consecutive + l (m + 1) + b when consecutive >= 0.
    std::int64_t consecutive = -1;
    // The chains' remembered start directions and lengths in this layout (the momentum
    // projection's, kept for the next step's solve), and the positions they were made at;
    // lane l holds chain l's memo while memo_generation[l] is that memo's generation
    // (RodChain::DirectionsMemo).
    std::vector<double> memo_u, memo_r, memo_x;
    std::uint64_t memo_generation[width] = {};
  };
  struct Across {
    // The groups met so far: the same groups come at every step.
    std::vector<Group> groups;
    // Per solve: the free positions, the positions, their directions (differences first),
    // lengths and residual, the multipliers, the impulses.
    std::vector<double> x0, x, u, r, phi, z, impulse;
    std::vector<double> v;  // the momentum projection's velocities
  } across;
  std::vector<double> lower, diagonal, upper, rhs, x, c;
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

  // Momentum projection at positions x: p <- p + C(x) mu with C(x)^T M^-1 p = 0; adds the rods'
  // virial terms mu_k |x_i - x_j| to `virial` in row order (the caller passes 0 and adds the
  // chain's sum as one term, as solve_positions' virial). Returns false (p untouched) when the
  // generic path must take over.
  [[nodiscard]] bool project_momenta(const Vec3* x, Vec3* p, const Box& box, RodChainWorkspace& ws,
                                     double& virial) const;

  // solve_positions for chains[0..count) at once (count <= RodChainLanes::width, every
  // chain with the same number of rods), every pass with one chain per vector lane
  // (rod_passes::across); every lane's numbers are solve_positions' own. solved[l]: whether
  // chain l's results were written (impulse, virial[l], status[l]). A chain that needs a
  // line-search halving, more iterations than allowed or the generic path, or whose line-search
  // test falls within rounding of its bound (the merit is summed in another order here), is
  // left unsolved: the caller solves it alone with solve_positions (which redoes it from the
  // start).
  static void solve_positions_lanes(const RodChain* const* chains, std::size_t count, const Vec3* q,
                                    const Vec3* delta, double h, const Box& box, double tolerance,
                                    int max_iterations, RodChainLanes& lanes, Vec3* impulse,
                                    double* virial, SolverStatus* status, bool* solved);
  // project_momenta for chains[0..count) at once, likewise; chain l's virial (its terms
  // summed from 0 in row order) goes to virial[l]. An unsolved chain's p is untouched: the
  // caller projects it alone with project_momenta.
  static void project_momenta_lanes(const RodChain* const* chains, std::size_t count, const Vec3* x,
                                    Vec3* p, const Box& box, RodChainLanes& lanes, double* virial,
                                    bool* solved);

  // max_k |r_k - L_k| / L_k over the rods at positions x (indexed globally), at least
  // `start` (not negative): the number a loop over the rows with gap_of would give, bit for
  // bit. Remembered with the directions last computed at these positions (the momentum
  // projection's, at the end of a step) when x is bit for bit where they were computed, else
  // computed.
  double largest_relative_deviation(const Vec3* x, const Box& box, RodChainWorkspace& ws,
                                    double start) const;
  // max_k |r_k - L_k| / L_k at the positions of the last momentum projection that returned
  // true (project_momenta, or project_momenta_lanes with the chain solved): what
  // largest_relative_deviation gives there from 0.
  double measured_deviation() const { return memo_.largest_deviation; }

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
  // differences() where a rod left its last image: every image rounded anew.
  void rewrap_differences(const double* x, const Box& box, double* d, double* d2) const;
  // differences(), and in the same pass an upper bound, from the squared lengths d2 alone (no
  // square roots), on max_k |r_k - L_k| as directions() and the residual would compute it;
  // +inf when that bound exceeds `tolerance` for some rod (or d2 is not finite).
  double differences_and_bound(const double* x, const Box& box, double* d, double* d2,
                               double tolerance, RodChainWorkspace& ws) const;
  // The phases of solve_positions. Gathers the step's start and free positions, the start
  // directions, and the residual at the free positions: true when the rods are held there.
  bool begin_positions(const Vec3* q, const Vec3* delta, double h, const Box& box, double tolerance,
                       RodChainWorkspace& ws, SolverStatus& status) const;
  // Whether the rods at x, whose differences and squared lengths u, r hold and whose
  // differences_and_bound is `bound`, are proven held (with the residual's norm below
  // `merit_cap` too) without their square roots; otherwise u, r, phi become the directions,
  // lengths and residual at x, and phi_norm residual_norm(phi).
  bool held_or_residual(double bound, Eigen::VectorXd& phi, double& phi_norm,
                        std::vector<double>& u, std::vector<double>& r, double merit_cap,
                        double tolerance, SolverStatus& status) const;
  // ws.phi's squared norm, made once per residual.
  static double merit(RodChainWorkspace& ws);
  // After the Newton step ws.step: the line search (at most `halvings` halvings).
  enum class LineSearch { held, descended, failed };
  LineSearch line_search(const Box& box, double tolerance, int halvings, RodChainWorkspace& ws,
                         SolverStatus& status) const;
  // One trial of the line search, the multipliers ws.trial: taken (held or descended, below
  // `merit_cap`) or failed (nothing taken).
  LineSearch try_trial(const Box& box, double tolerance, double merit_cap, RodChainWorkspace& ws,
                       SolverStatus& status) const;
  // Per bead, the impulse C z of the multipliers ws.z along the remembered directions, into
  // ws.impulse (x, y, z blocks of beads() each).
  void bead_impulses(RodChainWorkspace& ws) const;
  // The impulses C(q) z and the virial of a converged solve.
  void finish_positions(RodChainWorkspace& ws, Vec3* impulse, double& virial) const;
  // Gathers the velocities at positions x, remembers x's directions and makes RATTLE's
  // right-hand side in ws.pt.
  void begin_momenta(const Vec3* x, const Vec3* p, const Box& box, RodChainWorkspace& ws) const;
  // Adds the impulses C(x) mu (mu in ws.z) to p and the virial terms to `virial`.
  void finish_momenta(RodChainWorkspace& ws, Vec3* p, double& virial) const;
  // The group of chains[0..count) with step h from lanes.across.groups, made if new (lanes
  // past count repeat chain 0).
  static RodChainLanes::Group& group_of(const RodChain* const* chains, std::size_t count, double h,
                                        RodChainLanes& lanes);
  // The group of chains[0..count) in lanes.across.groups, or null.
  static RodChainLanes::Group* find_group(const RodChain* const* chains, std::size_t count,
                                          RodChainLanes& lanes);
  // Remembers the directions and lengths made in lane `lane` of lanes.across at the positions
  // there, which the caller then moves into group.memo_u, memo_r and memo_x; `largest` is
  // their largest_deviation.
  void remember_across(const Box& box, std::size_t lane, RodChainLanes::Group& group,
                       double largest) const;
  // Lane `lane` of group.memo_u and memo_r: the start directions and lengths of this solve
  // (memo_, made where not remembered). `same`: whether the lane's positions q are its
  // memo_x bit for bit (the solve's gather compared them).
  void begin_across(const Vec3* q, const Box& box, std::size_t lane, RodChainLanes::Group& group,
                    RodChainLanes& lanes, bool same) const;
  // rewrap_differences for lane `lane` at positions x (lane-major), into lanes.across.
  void rewrap_across(const double* x, const Box& box, std::size_t lane, RodChainLanes::Group& group,
                     RodChainLanes::Across& across) const;
  // The interleaved arrays sized for chains of `rows` rods.
  static void size_lanes(std::size_t rows, RodChainLanes& lanes);
  // The lanes' interleaved band entries solved (rod_passes::eliminate_lanes): solution k of
  // lane l at lanes.x[k * width + l]; lanes.solved[l]: whether lane l's elimination succeeded.
  static void eliminate_lanes(std::size_t rows, RodChainLanes& lanes);
  // The band entries and right-hand side solve_coupled eliminates, into ws.
  void make_bands(const double* a, const double* b, double scale, const Eigen::VectorXd& minus_rhs,
                  RodChainWorkspace& ws) const;
  // Solves (scale A) x = -minus_rhs for the Newton (and RATTLE) matrix
  // A = sum_p w_p s_k s_l a_k . b_l, tridiagonal (a, b: directions in chain order). False
  // when a pivot vanishes or x is not finite (the generic path takes over).
  [[nodiscard]] bool solve_coupled(const double* a, const double* b, double scale,
                                   const Eigen::VectorXd& minus_rhs, Eigen::VectorXd& x,
                                   RodChainWorkspace& ws) const;
  // Whether the memo is valid for this box and this chain's size.
  bool memo_in(const Box& box) const;
  // Whether memo_ holds the directions at these positions (indexed globally) in this box:
  // the last momentum projection's (or solve's) when they are bit for bit the positions it
  // had, as they are unless the neighbour list wrapped them in between.
  bool remembers(const Vec3* global, const Box& box) const;
  // The positions of the chain's particles into the memo (bead order).
  void remember_positions(const Vec3* global, const Box& box) const;
  // The box's periods into the memo, which starts a new generation (its positions kept
  // elsewhere or set by the caller).
  void remember_box(const Box& box) const;
  // Computes the directions and lengths at positions x (chain order, gathered from `global`)
  // into memo_.
  void remember_directions(const std::vector<double>& x, const Vec3* global, const Box& box) const;
  // max_k |r_k - L_k| / L_k over the lengths r (chain order), from 0 in row order.
  double largest_deviation(const double* r) const;

  // The last directions computed at a step's end or start positions, with those positions
  // and the box's periods: directions() is a function of these alone. The positions per bead
  // as they lie in the global array, so that the check is a comparison of memory (one block
  // when the chain's particles are consecutive). u, r and x in chain order unless `in_lanes`:
  // then only a group's lane holds them (RodChainLanes::Group::memo_generation; the positions
  // are compared there as the solve gathers its own), and a solve alone makes them again (the
  // same numbers). Each remembering starts a new generation.
  // Mutable: a cache, invisible in the results (a chain is solved by one thread at a time;
  // threads solve different chains).
  struct DirectionsMemo {
    bool valid = false, in_lanes = false;
    std::uint64_t generation = 0;
    std::vector<Vec3> x;
    std::vector<double> u, r;
    double largest_deviation = 0.0;
    Vec3 period, inverse_period;
  };
  mutable DirectionsMemo memo_;
  // Per rod and axis: the periodic image (in periods) its last minimum image subtracted,
  // tried first by differences(). Mutable like memo_: a cache that never changes a number.
  mutable std::vector<double> image_;

  // Whether bead b is particle bead_particle_[0] + b for every b.
  bool consecutive_ = false;
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
