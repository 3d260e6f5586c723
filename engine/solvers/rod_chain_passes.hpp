#pragma once

#include <cstddef>
#include <cstdint>

namespace deli::rod_passes {

// The per-rod and per-bead passes of RodChain on structure-of-arrays data in chain order:
// bead b at path position b, rod k between beads k and k+1; a vector of m entries per
// component is stored as x[0..m), y[m..2m), z[2m..3m). Each lane does the operations the
// scalar code did for its rod or bead, in the same order, so the loops vectorise without
// changing a bit (no fused multiply-add: -ffp-contract=off; IEEE sqrt and division are
// correctly rounded in vector form too). Their file alone is built for the build machine's
// CPU (DELI_NATIVE) and without errno from sqrt, so it includes no Eigen and no templates
// the rest of the engine would share.

// Differences d_k = x_i - x_j - period image_k of the rods (forward[k] > 0: i is bead k,
// else bead k+1; a double, so that the choice is a vector comparison) and their squared lengths d2;
// true when every |d_k| is within `limit` per axis (the images hold). x: 3(m+1) entries, image and
// d: 3m.
bool differences(std::size_t m, const double* x, const double* forward, const double* image,
                 const double* period, const double* limit, double* d, double* d2);

// differences() and held_bounds() of its squared lengths in one pass.
bool differences_and_bounds(std::size_t m, const double* x, const double* forward,
                            const double* image, const double* period, const double* limit,
                            const double* length, const double* inverse_length, double tolerance,
                            double* d, double* d2, double* bound, std::uint8_t* usable);

// d2 -> r = sqrt(d2) and d -> d / r (0 where r is not positive), in place.
void normalize(std::size_t m, double* d, double* r);
// normalize(), the residual phi = r - length, and residual_norm(phi) (solver_status.hpp):
// max |phi_k|, +inf unless every phi_k is finite.
double normalize_residual(std::size_t m, double* d, double* r, const double* length, double* phi);

// Per rod: the bound RodChain::held_bound takes the maximum of, and whether it may be used
// (0 or 1).
void held_bounds(std::size_t m, const double* d2, const double* length,
                 const double* inverse_length, double tolerance, double* bound,
                 std::uint8_t* usable);

// Impulse on every bead from the rods' directions u and multipliers z: 0 + u_a (s_a z_a)
// (+ u_b (s_b z_b)) over its rods a < b with their signs (first_sign, second_sign per bead).
// With hw (h times the bead's inverse mass), x0 + impulse hw instead. out: 3(m+1) entries.
void impulses(std::size_t m, const double* u, const double* z, const double* first_sign,
              const double* second_sign, double* out);
void positions(std::size_t m, const double* x0, const double* u, const double* z,
               const double* first_sign, const double* second_sign, const double* hw, double* out);

// The band entries of the Newton (RATTLE) matrix as ClusterRows::coupling_bands makes them:
// diagonal 0 + w_low d + w_high d with d = a_k . b_k, upper 0 + coupling_k a_k . b_{k+1},
// lower 0 + coupling_{k-1} a_k . b_{k-1}, each times scale; rhs = -minus_rhs.
void bands(std::size_t m, const double* a, const double* b, const double* w_low,
           const double* w_high, const double* coupling, double scale, const double* minus_rhs,
           double* lower, double* diagonal, double* upper, double* rhs);

// RATTLE's right-hand side: 0 + s_low u_k . v_low + s_high u_k . v_high per rod (low_first[k] > 0:
// the lower numbered bead is bead k, else bead k+1). v: 3(m+1) entries.
void projections(std::size_t m, const double* u, const double* v, const double* low_first,
                 const double* low_sign, const double* high_sign, double* out);

// Chains solved in lockstep, one per lane: a tridiagonal elimination is a chain of
// dependent divisions, so `lanes` chains of the same number of rods share each vector step.
constexpr std::size_t lanes = 8;

// solve_tridiagonal_twisted (tridiagonal.hpp) for `lanes` systems of n rows at once, every
// lane by the same operations in the same order: bands, rhs, x and c (scratch) hold entry
// (k, lane) at k * lanes + lane. solved[lane]: 1 where the template would return true.
void eliminate_lanes(std::size_t n, const double* lower, const double* diagonal,
                     const double* upper, const double* rhs, double* x, double* c,
                     std::uint8_t* solved);

}  // namespace deli::rod_passes

namespace deli::rod_passes::across {

// The position solve of `lanes` chains of m rods each in lane-major order: entry (k, lane) at
// k * lanes + lane, component c of a per-rod vector at (c m + k) lanes + lane, of a per-bead
// vector at (c (m+1) + b) lanes + lane. Every pass is the per-chain pass above with the
// chains side by side: each lane does its chain's operations in the same order, and the
// loops run over whole vectors of lanes (no tails, no per-chain loop overhead). Per-lane
// results (`per_lane`) have `lanes` entries.

// differences(); hold[lane]: whether every rod of the lane is within its image's range.
void differences(std::size_t m, const double* x, const double* forward, const double* image,
                 const double* period, const double* limit, double* d, double* d2,
                 std::uint8_t* hold);
// Per lane, max_k of held_bounds' bound, +inf where a rod is not usable.
void held_bound(std::size_t m, const double* d2, const double* length, const double* inverse_length,
                double tolerance, double* per_lane);
// normalize_residual(): per lane residual_norm of phi, and sum_k phi_k^2 in row order (not
// Eigen's order: an estimate of the merit within rounding).
void normalize_residual(std::size_t m, double* d, double* r, const double* length, double* phi,
                        double* norm, double* merit);
// rod_passes::bands() (rhs = -phi) solved by eliminate_lanes (the same numbers), each entry made as
// the elimination reaches its row.
void solve_bands(std::size_t m, const double* a, const double* b, const double* w_low,
                 const double* w_high, const double* coupling, double scale, const double* phi,
                 double* x, double* c, std::uint8_t* solved);
// impulses().
void impulses(std::size_t m, const double* u, const double* z, const double* first_sign,
              const double* second_sign, double* out);
// What measure_residual and advance_and_measure read: the group's constants (per rod:
// forward, image, length, inverse_length; per bead: first_sign, second_sign, hw), the box's
// periods and image limits, the tolerance; for advance_and_measure also the multipliers z (made
// z + step in the lanes where take[lane]), the free positions x0 and the start directions u,
// and where the impulses() of the multipliers z go (per bead, made with the positions) unless
// null.
struct Measured {
  std::size_t m;
  const double *forward, *image, *period, *limit, *length, *inverse_length;
  double tolerance;
  double* z;
  const double *step, *x0, *u, *first_sign, *second_sign, *hw;
  const std::uint8_t* take;
  double* impulse = nullptr;
};
// differences() at positions x into d and r, hold and held_bound()'s bound, then
// normalize_residual() (d, r, phi, norm, merit) in one pass, the same numbers. Where a lane's
// images do not hold, its differences are to be made again (rewrapped) and all of it after them.
void measure_residual(const Measured& in, const double* x, double* d, double* r, std::uint8_t* hold,
                      double* bound, double* phi, double* norm, double* merit);
// A Newton trial: z + step in the lanes where take[lane] (line_search's first trial: 1 step is
// the step), positions() of the per-chain passes into x, then as measure_residual, or without
// phi (null) only differences() and held_bound().
void advance_and_measure(const Measured& in, double* x, double* d, double* r, std::uint8_t* hold,
                         double* bound, double* phi, double* norm, double* merit);
// The momentum projection's passes over the rods at once, from differences d and squared
// lengths r (differences() or a rewrap): rod_passes::normalize() in place, per lane max_k |r_k -
// length_k| / length_k (from 0 in row order, by std::max), rod_passes::projections() of the
// velocities v and bands() of a = b = d (scale 1), each value by those passes' operations.
void project_rows(std::size_t m, double* d, double* r, const double* length, const double* v,
                  const double* low_first, const double* low_sign, const double* high_sign,
                  const double* w_low, const double* w_high, const double* coupling,
                  double* largest_deviation, double* lower, double* diagonal, double* upper,
                  double* rhs);
// Per lane, 0 + sum_k z_k r_k in row order (finish_positions' virial).
void virial(std::size_t m, const double* z, const double* r, double* per_lane);

// Between per-particle vectors (3 doubles a particle, as Vec3) and per-bead vectors of the
// lanes' n beads, lane l's bead b being particle[b * lanes + l]: whole rows of lanes at once,
// each entry by the operations of the lane-by-lane copies. base >= 0: lane l's bead b is
// particle base + l n + b (consecutive chains), which they exploit.
// out = a + b per component (a first: x0 = delta + q). With `memo` (this layout), same[l]
// tells whether lane l's b is memo's lane l bit for bit (a zero's sign too), else 0.
void gather_sum(std::size_t n, const std::int32_t* particle, std::int64_t base, const double* a,
                const double* b, double* out, const double* memo = nullptr,
                std::uint8_t* same = nullptr);
// x_out = x, v_out = p times the bead's inverse mass (lane-major, n entries).
void gather_velocities(std::size_t n, const std::int32_t* particle, std::int64_t base,
                       const double* x, const double* p, const double* inverse_mass, double* x_out,
                       double* v_out);
// out[particle] = in, or (add) out[particle] + in, in the lanes where take[lane].
void scatter(std::size_t n, const std::int32_t* particle, std::int64_t base, const double* in,
             const std::uint8_t* take, bool add, double* out);

}  // namespace deli::rod_passes::across
