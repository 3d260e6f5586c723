#include "solvers/rod_chain.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "solvers/rod_chain_passes.hpp"
#include "solvers/tridiagonal.hpp"

namespace deli {

std::unique_ptr<RodChain> RodChain::make(const LocalCluster& cluster) {
  const std::size_t m = cluster.rows.size();
  const std::size_t n = cluster.size();
  if (m == 0 || n != m + 1) return nullptr;
  // Per rod: particles i (+u) and j (-u); per particle: its rods in row order with their
  // signs (-1: none).
  std::vector<std::int32_t> i(m), j(m);
  // rows_of[2p], rows_of[2p + 1]: particle p's first and second rod.
  std::vector<std::int32_t> rows_of(2 * n, -1);
  std::vector<double> first_sign(n, 0.0), second_sign(n, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    const Constraint& row = cluster.rows[k];
    if (row.kind != ConstraintKind::rod || row.i < 0 || row.j < 0 || row.i == row.j) return nullptr;
    i[k] = row.i;
    j[k] = row.j;
    for (const auto& [p, sign] : {std::pair{row.i, 1.0}, std::pair{row.j, -1.0}}) {
      if (rows_of[2 * p] < 0) {
        rows_of[2 * p] = static_cast<std::int32_t>(k);
        first_sign[p] = sign;
      } else if (rows_of[2 * p + 1] < 0 && rows_of[2 * p] + 1 == static_cast<std::int32_t>(k)) {
        rows_of[2 * p + 1] = static_cast<std::int32_t>(k);
        second_sign[p] = sign;
      } else {
        return nullptr;  // a third rod on a particle, or two rods not consecutive
      }
    }
  }
  for (std::size_t p = 0; p < n; ++p) {
    if (rows_of[2 * p] < 0) return nullptr;  // a particle no rod touches
  }
  // Chain order: bead k + 1 is the particle rods k and k + 1 share (exactly one); the ends
  // are rod 0's other particle and rod m-1's other particle (a lone rod: i, then j).
  std::vector<std::int32_t> path;
  path.reserve(n);
  for (std::size_t k = 0; k + 1 < m; ++k) {
    const bool i_shared = rows_of[2 * i[k] + 1] == static_cast<std::int32_t>(k + 1);
    const bool j_shared = rows_of[2 * j[k] + 1] == static_cast<std::int32_t>(k + 1);
    if (i_shared == j_shared) return nullptr;
    if (k == 0) path.push_back(i_shared ? j[0] : i[0]);
    path.push_back(i_shared ? i[k] : j[k]);
  }
  if (m == 1) path.push_back(i[0]);
  path.push_back(i[m - 1] == path.back() ? j[m - 1] : i[m - 1]);

  std::unique_ptr<RodChain> chain(new RodChain());
  RodChain& c = *chain;
  for (std::size_t b = 0; b < n; ++b) {
    const std::int32_t p = path[b];
    c.bead_particle_.push_back(cluster.particles[p]);
    c.bead_inverse_mass_.push_back(cluster.inverse_mass[p]);
    c.first_sign_.push_back(first_sign[p]);
    c.second_sign_.push_back(rows_of[2 * p + 1] >= 0 ? second_sign[p] : 0.0);
  }
  for (std::size_t k = 0; k < m; ++k) {
    const bool forward = i[k] == path[k];
    if (!(forward ? j[k] == path[k + 1] : i[k] == path[k + 1] && j[k] == path[k])) return nullptr;
    const Constraint& row = cluster.rows[k];
    const bool i_first = row.i < row.j;
    const std::int32_t low = i_first ? row.i : row.j;
    c.forward_.push_back(forward ? 1.0 : 0.0);
    c.low_first_.push_back(low == path[k] ? 1.0 : 0.0);
    c.length_.push_back(row.length);
    c.inverse_length_.push_back(1.0 / row.length);
    c.low_sign_.push_back(i_first ? 1.0 : -1.0);
    c.high_sign_.push_back(i_first ? -1.0 : 1.0);
    c.w_low_.push_back(cluster.inverse_mass[low]);
    c.w_high_.push_back(cluster.inverse_mass[i_first ? row.j : row.i]);
    // The shared bead's sign product (its two rods) times its inverse mass, as
    // ClusterRows::coupling_bands multiplies them.
    const std::int32_t shared = k + 1 < m ? path[k + 1] : -1;
    c.coupling_.push_back(shared >= 0 ? first_sign[shared] * second_sign[shared] *
                                            cluster.inverse_mass[shared]
                                      : 0.0);
  }
  c.image_.assign(3 * m, 0.0);
  return chain;
}

void RodChain::gather(const Vec3* global, std::vector<double>& out) const {
  const std::size_t n = beads();
  out.resize(3 * n);
  for (std::size_t b = 0; b < n; ++b) {
    const Vec3& v = global[bead_particle_[b]];
    out[b] = v.x;
    out[n + b] = v.y;
    out[2 * n + b] = v.z;
  }
}

void RodChain::directions(const double* x, const Box& box, double* u, double* r) const {
  differences(x, box, u, r);
  rod_passes::normalize(rows(), u, r);
}

// Two passes over the rods (this one, then normalize), so that the square roots and the
// divisions of successive rods overlap; the same operations as norm() and d / |d|. The
// minimum image with each rod's last periodic image n: d - period n is
// Box::minimum_image(d), operation for operation, whenever rounding d / period would give n,
// as it does when |d - period n| <= 0.4 period on every periodic axis (d / period within 0.4
// of n, and the rounding of the division far below 0.1). Only when a rod leaves that range
// (a particle was wrapped, or a first call) is the image rounded anew, for the whole pass.
void RodChain::differences(const double* x, const Box& box, double* d, double* d2) const {
  const std::size_t m = rows();
  const std::size_t n = beads();
  const Vec3 period = box.period();
  constexpr double open = std::numeric_limits<double>::infinity();
  const double periods[3] = {period.x, period.y, period.z};
  const double limit[3] = {period.x > 0 ? 0.4 * period.x : open,
                           period.y > 0 ? 0.4 * period.y : open,
                           period.z > 0 ? 0.4 * period.z : open};
  if (rod_passes::differences(m, x, forward_.data(), image_.data(), periods, limit, d, d2)) return;
  const Vec3& inverse_period = box.inverse_period();
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t a = forward_[k] > 0 ? k : k + 1;
    const std::size_t b = forward_[k] > 0 ? k + 1 : k;
    const Vec3 e = Vec3{x[a], x[n + a], x[2 * n + a]} - Vec3{x[b], x[n + b], x[2 * n + b]};
    image_[k] = Box::round_to_integer(e.x * inverse_period.x);
    image_[m + k] = Box::round_to_integer(e.y * inverse_period.y);
    image_[2 * m + k] = Box::round_to_integer(e.z * inverse_period.z);
    const Vec3 image = box.minimum_image(e);
    d[k] = image.x;
    d[m + k] = image.y;
    d[2 * m + k] = image.z;
    d2[k] = norm2(image);
  }
}

// The residual r_k - L_k with r_k = fl(sqrt(d2_k)) obeys, for d2_k within a quarter of L_k^2
// (so that d2_k - fl(L_k^2) and r_k - L_k are exact subtractions, Sterbenz):
//   |r_k - L_k| <= |sqrt(d2_k) - L_k| + |r_k - sqrt(d2_k)|
//              <= (|fl(d2_k - fl(L_k^2))| + L_k^2 2^-53) / L_k + sqrt(d2_k) 2^-53
//              <= fl(|d2_k - fl(L_k^2)| fl(1 / L_k)) (1 + 2^-51) + L_k 2^-51,
// as |sqrt(d2) - L| = |d2 - L^2| / (sqrt(d2) + L) <= |d2 - L^2| / L. The bound
// (rod_passes::held_bounds) rounds with slack 2^-50 on both terms, above all rounding of its
// own evaluation.
double RodChain::held_bound(const double* d2, double tolerance, RodChainWorkspace& ws) const {
  const std::size_t m = rows();
  ws.bounds.resize(m);
  ws.usable.resize(m);
  rod_passes::held_bounds(m, d2, length_.data(), inverse_length_.data(), tolerance,
                          ws.bounds.data(), ws.usable.data());
  double bound = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    if (!ws.usable[k]) return std::numeric_limits<double>::infinity();
    bound = std::max(bound, ws.bounds[k]);
  }
  return bound;
}

// The band entries ClusterRows::coupling_bands makes (rod_passes::bands: the same
// operations in the same order), without the per-cluster containers.
void RodChain::make_bands(const double* a, const double* b, double scale,
                          const Eigen::VectorXd& minus_rhs, RodChainWorkspace& ws) const {
  const std::size_t m = rows();
  ws.lower.resize(m);
  ws.diagonal.resize(m);
  ws.upper.resize(m);
  ws.rhs.resize(m);
  rod_passes::bands(m, a, b, w_low_.data(), w_high_.data(), coupling_.data(), scale,
                    minus_rhs.data(), ws.lower.data(), ws.diagonal.data(), ws.upper.data(),
                    ws.rhs.data());
}

// solve_tridiagonal's elimination of those bands.
bool RodChain::solve_coupled(const double* a, const double* b, double scale,
                             const Eigen::VectorXd& minus_rhs, Eigen::VectorXd& x,
                             RodChainWorkspace& ws) const {
  const std::size_t m = rows();
  x.resize(static_cast<Eigen::Index>(m));
  ws.pivots.resize(static_cast<Eigen::Index>(m));
  make_bands(a, b, scale, minus_rhs, ws);
  const double* lower = ws.lower.data();
  const double* diagonal = ws.diagonal.data();
  const double* upper = ws.upper.data();
  const double* rhs = ws.rhs.data();
  return solve_tridiagonal_twisted(
      static_cast<Eigen::Index>(m), [lower](Eigen::Index k) { return lower[k]; },
      [diagonal](Eigen::Index k) { return diagonal[k]; },
      [upper](Eigen::Index k) { return upper[k]; }, [rhs](Eigen::Index k) { return rhs[k]; },
      x.data(), ws.pivots.data());
}

void RodChain::solve_lanes(std::size_t m, const bool* solving, RodChainLanes& lanes, bool into_z) {
  constexpr std::size_t w = RodChainLanes::width;
  static_assert(w == rod_passes::lanes);
  lanes.lower.resize(m * w);
  lanes.diagonal.resize(m * w);
  lanes.upper.resize(m * w);
  lanes.rhs.resize(m * w);
  lanes.x.resize(m * w);
  lanes.c.resize(m * w);
  // Lanes not solving keep whatever their slots held (initialised, never read back).
  for (std::size_t l = 0; l < w; ++l) {
    if (!solving[l]) continue;
    const RodChainWorkspace& ws = lanes.lane[l];
    // Entries lower(0) and upper(m-1) are never made nor read.
    for (std::size_t k = 1; k < m; ++k) lanes.lower[k * w + l] = ws.lower[k];
    for (std::size_t k = 0; k < m; ++k) lanes.diagonal[k * w + l] = ws.diagonal[k];
    for (std::size_t k = 0; k + 1 < m; ++k) lanes.upper[k * w + l] = ws.upper[k];
    for (std::size_t k = 0; k < m; ++k) lanes.rhs[k * w + l] = ws.rhs[k];
  }
  rod_passes::eliminate_lanes(m, lanes.lower.data(), lanes.diagonal.data(), lanes.upper.data(),
                              lanes.rhs.data(), lanes.x.data(), lanes.c.data(), lanes.solved);
  for (std::size_t l = 0; l < w; ++l) {
    if (!solving[l] || !lanes.solved[l]) continue;
    Eigen::VectorXd& out = into_z ? lanes.lane[l].z : lanes.lane[l].step;
    out.resize(static_cast<Eigen::Index>(m));
    for (std::size_t k = 0; k < m; ++k) out(static_cast<Eigen::Index>(k)) = lanes.x[k * w + l];
  }
}

bool RodChain::remembered_at(const std::vector<double>& x, const Box& box) const {
  const DirectionsMemo& memo = memo_;
  return memo.valid && memo.period.x == box.period().x && memo.period.y == box.period().y &&
         memo.period.z == box.period().z && memo.inverse_period.x == box.inverse_period().x &&
         memo.inverse_period.y == box.inverse_period().y &&
         memo.inverse_period.z == box.inverse_period().z && memo.x.size() == x.size() &&
         std::memcmp(memo.x.data(), x.data(), x.size() * sizeof(double)) == 0;
}

void RodChain::start_directions(const std::vector<double>& q, const Box& box) const {
  if (!remembered_at(q, box)) remember_directions(q, box);
}

void RodChain::remember_directions(const std::vector<double>& x, const Box& box) const {
  memo_.u.resize(3 * rows());
  memo_.r.resize(rows());
  directions(x.data(), box, memo_.u.data(), memo_.r.data());
  memo_.x = x;
  memo_.period = box.period();
  memo_.inverse_period = box.inverse_period();
  memo_.valid = true;
}

bool RodChain::held_or_residual(Eigen::VectorXd& phi, std::vector<double>& u,
                                std::vector<double>& r, double merit_cap, double tolerance,
                                RodChainWorkspace& ws, SolverStatus& status) const {
  const std::size_t m = rows();
  const double bound = held_bound(r.data(), tolerance, ws);
  // sum_k phi_k^2 <= m bound^2; the factor 2 covers the rounding of Eigen's sum. The
  // residual, then computed, would show the rods held: the iteration would take the same
  // course. At the last position of a solve this saves the square roots and divisions of
  // one directions pass.
  if (bound <= tolerance && static_cast<double>(m) * bound * bound * 2 <= merit_cap) {
    status.residual = bound;
    return true;
  }
  rod_passes::normalize(m, u.data(), r.data());
  phi.resize(static_cast<Eigen::Index>(m));
  for (std::size_t k = 0; k < m; ++k) phi(static_cast<Eigen::Index>(k)) = r[k] - length_[k];
  return false;
}

bool RodChain::begin_positions(const Vec3* q, const Vec3* delta, double h, const Box& box,
                               double tolerance, RodChainWorkspace& ws,
                               SolverStatus& status) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  gather(q, ws.q);
  ws.x0.resize(3 * n);
  ws.x.resize(3 * n);
  ws.xt.resize(3 * n);
  ws.hw.resize(n);
  ws.ux.resize(3 * m);
  ws.uxt.resize(3 * m);
  ws.rx.resize(m);
  ws.rxt.resize(m);
  for (std::size_t b = 0; b < n; ++b) {
    const std::int32_t g = bead_particle_[b];
    ws.x0[b] = delta[g].x + q[g].x;
    ws.x0[n + b] = delta[g].y + q[g].y;
    ws.x0[2 * n + b] = delta[g].z + q[g].z;
    ws.hw[b] = h * bead_inverse_mass_[b];
  }
  // Directions of the impulses: the rods at the start of the step, fixed.
  start_directions(ws.q, box);
  status = SolverStatus{};
  ws.z.setZero(static_cast<Eigen::Index>(m));
  // positions(z = 0): a zero impulse adds +0 to x0, which leaves it as it is.
  ws.x = ws.x0;
  differences(ws.x.data(), box, ws.ux.data(), ws.rx.data());
  return held_or_residual(ws.phi, ws.ux, ws.rx, std::numeric_limits<double>::infinity(), tolerance,
                          ws, status);
}

RodChain::LineSearch RodChain::line_search(const Box& box, double tolerance, int halvings_allowed,
                                           RodChainWorkspace& ws, SolverStatus& status) const {
  const std::size_t m = rows();
  const double merit = ws.phi.squaredNorm();
  double t = 1.0;
  for (int halvings = 0;; ++halvings) {
    ws.trial = ws.z + t * ws.step;
    rod_passes::positions(m, ws.x0.data(), memo_.u.data(), ws.trial.data(), first_sign_.data(),
                          second_sign_.data(), ws.hw.data(), ws.xt.data());
    const double merit_cap = (1 - 1e-4 * t) * merit;
    differences(ws.xt.data(), box, ws.uxt.data(), ws.rxt.data());
    if (held_or_residual(ws.pt, ws.uxt, ws.rxt, merit_cap, tolerance, ws, status)) {
      std::swap(ws.z, ws.trial);
      std::swap(ws.x, ws.xt);
      return LineSearch::held;
    }
    if (ws.pt.squaredNorm() <= merit_cap) {
      std::swap(ws.z, ws.trial);
      std::swap(ws.x, ws.xt);
      std::swap(ws.phi, ws.pt);
      std::swap(ws.ux, ws.uxt);
      std::swap(ws.rx, ws.rxt);
      return LineSearch::descended;
    }
    if (halvings == halvings_allowed) return LineSearch::failed;
    t *= 0.5;
  }
}

void RodChain::bead_impulses(RodChainWorkspace& ws) const {
  ws.impulse.resize(3 * beads());
  rod_passes::impulses(rows(), memo_.u.data(), ws.z.data(), first_sign_.data(), second_sign_.data(),
                       ws.impulse.data());
}

void RodChain::finish_positions(RodChainWorkspace& ws, Vec3* impulse, double& virial) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  bead_impulses(ws);
  for (std::size_t b = 0; b < n; ++b) {
    impulse[bead_particle_[b]] = {ws.impulse[b], ws.impulse[n + b], ws.impulse[2 * n + b]};
  }
  for (std::size_t k = 0; k < m; ++k) virial += ws.z(static_cast<Eigen::Index>(k)) * memo_.r[k];
}

bool RodChain::solve_positions(const Vec3* q, const Vec3* delta, double h, const Box& box,
                               double tolerance, int max_iterations, int line_search_limit,
                               RodChainWorkspace& ws, Vec3* impulse, double& virial,
                               SolverStatus& status) const {
  bool held = begin_positions(q, delta, h, box, tolerance, ws, status);
  while (!held) {
    status.residual = residual_norm(ws.phi);
    if (status.residual <= tolerance) break;
    if (status.iterations >= max_iterations) return false;
    ++status.iterations;
    // d gap_k / d z_l = h grad g_k(x)^T M^-1 C_l(q).
    if (!solve_coupled(ws.ux.data(), memo_.u.data(), h, ws.phi, ws.step, ws)) return false;
    const LineSearch outcome = line_search(box, tolerance, line_search_limit, ws, status);
    // No decrease: the generic path reports.
    if (outcome == LineSearch::failed) return false;
    held = outcome == LineSearch::held;
  }
  status.converged = true;
  finish_positions(ws, impulse, virial);
  return true;
}

void RodChain::solve_positions_lanes(const RodChain* const* chains, std::size_t count,
                                     const Vec3* q, const Vec3* delta, double h, const Box& box,
                                     double tolerance, int max_iterations, RodChainLanes& lanes,
                                     Vec3* impulse, double* virial, SolverStatus* status,
                                     bool* solved) {
  constexpr std::size_t w = RodChainLanes::width;
  const std::size_t m = count > 0 ? chains[0]->rows() : 0;
  // Per lane: still iterating, or done (converged).
  bool active[w] = {}, done[w] = {};
  for (std::size_t l = 0; l < count; ++l) {
    solved[l] = false;
    if (chains[l]->begin_positions(q, delta, h, box, tolerance, lanes.lane[l], status[l])) {
      done[l] = true;
    } else {
      active[l] = true;
    }
  }
  for (;;) {
    bool any = false;
    for (std::size_t l = 0; l < count; ++l) {
      if (!active[l]) continue;
      RodChainWorkspace& ws = lanes.lane[l];
      status[l].residual = residual_norm(ws.phi);
      if (status[l].residual <= tolerance) {
        active[l] = false;
        done[l] = true;
        continue;
      }
      if (status[l].iterations >= max_iterations) {
        active[l] = false;  // left to solve_positions (which gives up too)
        continue;
      }
      ++status[l].iterations;
      chains[l]->make_bands(ws.ux.data(), chains[l]->memo_.u.data(), h, ws.phi, ws);
      any = true;
    }
    if (!any) break;
    solve_lanes(m, active, lanes, false);
    for (std::size_t l = 0; l < count; ++l) {
      if (!active[l]) continue;
      // A vanishing pivot or a halving: solve_positions redoes the chain.
      const LineSearch outcome =
          lanes.solved[l] ? chains[l]->line_search(box, tolerance, 0, lanes.lane[l], status[l])
                          : LineSearch::failed;
      if (outcome == LineSearch::failed) {
        active[l] = false;
      } else if (outcome == LineSearch::held) {
        active[l] = false;
        done[l] = true;
      }
    }
  }
  for (std::size_t l = 0; l < count; ++l) {
    if (!done[l]) continue;
    status[l].converged = true;
    virial[l] = 0.0;
    chains[l]->finish_positions(lanes.lane[l], impulse, virial[l]);
    solved[l] = true;
  }
}

void RodChain::begin_momenta(const Vec3* x, const Vec3* p, const Box& box,
                             RodChainWorkspace& ws) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  gather(x, ws.x);
  ws.v.resize(3 * n);
  for (std::size_t b = 0; b < n; ++b) {
    const Vec3 v = p[bead_particle_[b]] * bead_inverse_mass_[b];
    ws.v[b] = v.x;
    ws.v[n + b] = v.y;
    ws.v[2 * n + b] = v.z;
  }
  // These positions start the next step unless the neighbour list wraps them meanwhile:
  // their directions are made where the next solve finds them.
  remember_directions(ws.x, box);
  // (C^T M^-1 C) mu = -C^T M^-1 p, C^T v summed over each rod's particles in their order.
  ws.pt.resize(static_cast<Eigen::Index>(m));
  rod_passes::projections(m, memo_.u.data(), ws.v.data(), low_first_.data(), low_sign_.data(),
                          high_sign_.data(), ws.pt.data());
}

void RodChain::finish_momenta(RodChainWorkspace& ws, Vec3* p, double* virial_terms) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  bead_impulses(ws);
  for (std::size_t b = 0; b < n; ++b) {
    p[bead_particle_[b]] += Vec3{ws.impulse[b], ws.impulse[n + b], ws.impulse[2 * n + b]};
  }
  for (std::size_t k = 0; k < m; ++k) {
    virial_terms[k] = ws.z(static_cast<Eigen::Index>(k)) * memo_.r[k];
  }
}

bool RodChain::project_momenta(const Vec3* x, Vec3* p, const Box& box, RodChainWorkspace& ws,
                               double* virial_terms) const {
  begin_momenta(x, p, box, ws);
  // Scale 1: multiplying by 1 leaves every entry as it is.
  if (!solve_coupled(memo_.u.data(), memo_.u.data(), 1.0, ws.pt, ws.z, ws)) return false;
  finish_momenta(ws, p, virial_terms);
  return true;
}

void RodChain::project_momenta_lanes(const RodChain* const* chains, std::size_t count,
                                     const Vec3* x, Vec3* p, const Box& box, RodChainLanes& lanes,
                                     bool* solved) {
  constexpr std::size_t w = RodChainLanes::width;
  const std::size_t m = count > 0 ? chains[0]->rows() : 0;
  bool solving[w] = {};
  for (std::size_t l = 0; l < count; ++l) {
    RodChainWorkspace& ws = lanes.lane[l];
    chains[l]->begin_momenta(x, p, box, ws);
    const double* u = chains[l]->memo_.u.data();
    chains[l]->make_bands(u, u, 1.0, ws.pt, ws);
    solving[l] = true;
  }
  solve_lanes(m, solving, lanes, true);
  lanes.virial_terms.resize(count * m);
  for (std::size_t l = 0; l < count; ++l) {
    solved[l] = lanes.solved[l] != 0;
    if (solved[l]) chains[l]->finish_momenta(lanes.lane[l], p, lanes.virial_terms.data() + l * m);
  }
}

double RodChain::largest_relative_deviation(const Vec3* x, const Box& box, RodChainWorkspace& ws,
                                            double start) const {
  const std::size_t m = rows();
  gather(x, ws.x);
  const std::vector<double>* r = &memo_.r;
  if (!remembered_at(ws.x, box)) {
    ws.ux.resize(3 * m);
    ws.rx.resize(m);
    directions(ws.x.data(), box, ws.ux.data(), ws.rx.data());
    r = &ws.rx;
  }
  // gap_of's rod gap, norm(minimum_image(x_i - x_j)) - L: directions' length minus L.
  double largest = start;
  for (std::size_t k = 0; k < m; ++k) {
    largest = std::max(largest, std::abs((*r)[k] - length_[k]) / length_[k]);
  }
  return largest;
}

}  // namespace deli
