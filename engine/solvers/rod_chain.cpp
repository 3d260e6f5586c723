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
  c.consecutive_ = true;
  for (std::size_t b = 0; b < n; ++b) {
    c.consecutive_ = c.consecutive_ && c.bead_particle_[b] == c.bead_particle_[0] + std::int32_t(b);
  }
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
namespace {
// The box's periods and the per-axis range within which a rod's last image still holds.
struct ImageRange {
  double periods[3], limit[3];
  explicit ImageRange(const Box& box) {
    const Vec3 period = box.period();
    constexpr double open = std::numeric_limits<double>::infinity();
    periods[0] = period.x;
    periods[1] = period.y;
    periods[2] = period.z;
    limit[0] = period.x > 0 ? 0.4 * period.x : open;
    limit[1] = period.y > 0 ? 0.4 * period.y : open;
    limit[2] = period.z > 0 ? 0.4 * period.z : open;
  }
};
}  // namespace

void RodChain::differences(const double* x, const Box& box, double* d, double* d2) const {
  const ImageRange range(box);
  if (rod_passes::differences(rows(), x, forward_.data(), image_.data(), range.periods, range.limit,
                              d, d2)) {
    return;
  }
  rewrap_differences(x, box, d, d2);
}

void RodChain::rewrap_differences(const double* x, const Box& box, double* d, double* d2) const {
  const std::size_t m = rows();
  const std::size_t n = beads();
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
double RodChain::differences_and_bound(const double* x, const Box& box, double* d, double* d2,
                                       double tolerance, RodChainWorkspace& ws) const {
  const std::size_t m = rows();
  ws.bounds.resize(m);
  ws.usable.resize(m);
  const ImageRange range(box);
  if (!rod_passes::differences_and_bounds(m, x, forward_.data(), image_.data(), range.periods,
                                          range.limit, length_.data(), inverse_length_.data(),
                                          tolerance, d, d2, ws.bounds.data(), ws.usable.data())) {
    rewrap_differences(x, box, d, d2);
    rod_passes::held_bounds(m, d2, length_.data(), inverse_length_.data(), tolerance,
                            ws.bounds.data(), ws.usable.data());
  }
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

void RodChain::size_lanes(std::size_t m, RodChainLanes& lanes) {
  constexpr std::size_t w = RodChainLanes::width;
  static_assert(w == rod_passes::lanes);
  // Slots of lanes not solving keep whatever they held (initialised, never read back), as do
  // entries lower(0) and upper(m-1), never made nor read.
  lanes.lower.resize(m * w);
  lanes.diagonal.resize(m * w);
  lanes.upper.resize(m * w);
  lanes.rhs.resize(m * w);
  lanes.x.resize(m * w);
  lanes.c.resize(m * w);
}

void RodChain::eliminate_lanes(std::size_t m, RodChainLanes& lanes) {
  rod_passes::eliminate_lanes(m, lanes.lower.data(), lanes.diagonal.data(), lanes.upper.data(),
                              lanes.rhs.data(), lanes.x.data(), lanes.c.data(), lanes.solved);
}

bool RodChain::memo_in(const Box& box) const {
  const DirectionsMemo& memo = memo_;
  return memo.valid && memo.period.x == box.period().x && memo.period.y == box.period().y &&
         memo.period.z == box.period().z && memo.inverse_period.x == box.inverse_period().x &&
         memo.inverse_period.y == box.inverse_period().y &&
         memo.inverse_period.z == box.inverse_period().z;
}

// Compared bit for bit (a zero's sign too), as the memo's positions were copied. A memo in
// lanes is compared there (begin_across).
bool RodChain::remembers(const Vec3* global, const Box& box) const {
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  if (memo_.in_lanes || !memo_in(box) || memo_.x.size() != beads()) return false;
  const std::size_t n = beads();
  if (consecutive_) {
    return std::memcmp(global + bead_particle_[0], memo_.x.data(), n * sizeof(Vec3)) == 0;
  }
  for (std::size_t b = 0; b < n; ++b) {
    if (std::memcmp(global + bead_particle_[b], &memo_.x[b], sizeof(Vec3)) != 0) return false;
  }
  return true;
}

void RodChain::remember_positions(const Vec3* global, const Box& box) const {
  const std::size_t n = beads();
  memo_.x.resize(n);
  if (consecutive_) {
    std::memcpy(memo_.x.data(), global + bead_particle_[0], n * sizeof(Vec3));
  } else {
    for (std::size_t b = 0; b < n; ++b) memo_.x[b] = global[bead_particle_[b]];
  }
  remember_box(box);
}

void RodChain::remember_box(const Box& box) const {
  memo_.period = box.period();
  memo_.inverse_period = box.inverse_period();
  memo_.valid = true;
  ++memo_.generation;
}

double RodChain::largest_deviation(const double* r) const {
  double largest = 0.0;
  for (std::size_t k = 0; k < rows(); ++k) {
    largest = std::max(largest, std::abs(r[k] - length_[k]) / length_[k]);
  }
  return largest;
}

void RodChain::remember_directions(const std::vector<double>& x, const Vec3* global,
                                   const Box& box) const {
  memo_.u.resize(3 * rows());
  memo_.r.resize(rows());
  directions(x.data(), box, memo_.u.data(), memo_.r.data());
  remember_positions(global, box);
  memo_.in_lanes = false;
  memo_.largest_deviation = largest_deviation(memo_.r.data());
}

bool RodChain::held_or_residual(double bound, Eigen::VectorXd& phi, double& phi_norm,
                                std::vector<double>& u, std::vector<double>& r, double merit_cap,
                                double tolerance, SolverStatus& status) const {
  const std::size_t m = rows();
  // sum_k phi_k^2 <= m bound^2; the factor 2 covers the rounding of Eigen's sum. The
  // residual, then computed, would show the rods held: the iteration would take the same
  // course. At the last position of a solve this saves the square roots and divisions of
  // one directions pass.
  if (bound <= tolerance && static_cast<double>(m) * bound * bound * 2 <= merit_cap) {
    status.residual = bound;
    return true;
  }
  phi.resize(static_cast<Eigen::Index>(m));
  phi_norm = rod_passes::normalize_residual(m, u.data(), r.data(), length_.data(), phi.data());
  return false;
}

bool RodChain::begin_positions(const Vec3* q, const Vec3* delta, double h, const Box& box,
                               double tolerance, RodChainWorkspace& ws,
                               SolverStatus& status) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  ws.x0.resize(3 * n);
  ws.xt.resize(3 * n);
  ws.hw.resize(n);
  ws.ux.resize(3 * m);
  ws.uxt.resize(3 * m);
  ws.rx.resize(m);
  ws.rxt.resize(m);
  // Directions of the impulses: the rods at the start of the step, fixed.
  if (!remembers(q, box) || memo_.in_lanes) {
    gather(q, ws.q);
    remember_directions(ws.q, q, box);
  }
  for (std::size_t b = 0; b < n; ++b) {
    const std::int32_t g = bead_particle_[b];
    ws.x0[b] = delta[g].x + q[g].x;
    ws.x0[n + b] = delta[g].y + q[g].y;
    ws.x0[2 * n + b] = delta[g].z + q[g].z;
    ws.hw[b] = h * bead_inverse_mass_[b];
  }
  status = SolverStatus{};
  ws.z.setZero(static_cast<Eigen::Index>(m));
  ws.merit = -1.0;
  // The residual at z = 0: a zero impulse adds +0 to x0, which leaves it as it is.
  const double bound =
      differences_and_bound(ws.x0.data(), box, ws.ux.data(), ws.rx.data(), tolerance, ws);
  return held_or_residual(bound, ws.phi, ws.phi_norm, ws.ux, ws.rx,
                          std::numeric_limits<double>::infinity(), tolerance, status);
}

double RodChain::merit(RodChainWorkspace& ws) {
  if (ws.merit < 0) ws.merit = ws.phi.squaredNorm();
  return ws.merit;
}

RodChain::LineSearch RodChain::try_trial(const Box& box, double tolerance, double merit_cap,
                                         RodChainWorkspace& ws, SolverStatus& status) const {
  const std::size_t m = rows();
  rod_passes::positions(m, ws.x0.data(), memo_.u.data(), ws.trial.data(), first_sign_.data(),
                        second_sign_.data(), ws.hw.data(), ws.xt.data());
  const double bound =
      differences_and_bound(ws.xt.data(), box, ws.uxt.data(), ws.rxt.data(), tolerance, ws);
  if (held_or_residual(bound, ws.pt, ws.pt_norm, ws.uxt, ws.rxt, merit_cap, tolerance, status)) {
    std::swap(ws.z, ws.trial);
    return LineSearch::held;
  }
  const double trial_merit = ws.pt.squaredNorm();
  if (!(trial_merit <= merit_cap)) return LineSearch::failed;
  std::swap(ws.z, ws.trial);
  std::swap(ws.phi, ws.pt);
  std::swap(ws.phi_norm, ws.pt_norm);
  std::swap(ws.ux, ws.uxt);
  std::swap(ws.rx, ws.rxt);
  ws.merit = trial_merit;
  return LineSearch::descended;
}

RodChain::LineSearch RodChain::line_search(const Box& box, double tolerance, int halvings_allowed,
                                           RodChainWorkspace& ws, SolverStatus& status) const {
  const double merit_now = merit(ws);
  double t = 1.0;
  for (int halvings = 0;; ++halvings) {
    ws.trial = ws.z + t * ws.step;
    const LineSearch outcome = try_trial(box, tolerance, (1 - 1e-4 * t) * merit_now, ws, status);
    if (outcome != LineSearch::failed) return outcome;
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
    status.residual = ws.phi_norm;
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

namespace {
// Copies lane `from` of a lane-major vector into lane `to`.
void copy_lane(std::vector<double>& v, std::size_t from, std::size_t to) {
  constexpr std::size_t w = RodChainLanes::width;
  for (std::size_t i = 0; i < v.size(); i += w) v[i + to] = v[i + from];
}
}  // namespace

RodChainLanes::Group* RodChain::find_group(const RodChain* const* chains, std::size_t count,
                                           RodChainLanes& lanes) {
  constexpr std::size_t w = RodChainLanes::width;
  const std::size_t m = chains[0]->rows();
  for (RodChainLanes::Group& g : lanes.across.groups) {
    bool same = g.rows == m;
    for (std::size_t l = 0; same && l < w; ++l) {
      same = g.chains[l] == (l < count ? chains[l] : nullptr);
    }
    if (same) return &g;
  }
  return nullptr;
}

RodChainLanes::Group& RodChain::group_of(const RodChain* const* chains, std::size_t count, double h,
                                         RodChainLanes& lanes) {
  constexpr std::size_t w = RodChainLanes::width;
  const std::size_t m = chains[0]->rows();
  const std::size_t n = m + 1;
  std::vector<RodChainLanes::Group>& groups = lanes.across.groups;
  RodChainLanes::Group* found = find_group(chains, count, lanes);
  if (found && found->h == h) return *found;
  if (!found) {
    // Chains regrouped (another partition, a subset solved again): start afresh past a bound.
    if (groups.size() >= 64) groups.clear();
    found = &groups.emplace_back();
    for (std::size_t l = 0; l < w; ++l) found->chains[l] = l < count ? chains[l] : nullptr;
    found->rows = m;
  }
  RodChainLanes::Group& g = *found;
  g.h = h;
  for (auto* v : {&g.forward, &g.length, &g.inverse_length, &g.w_low, &g.w_high, &g.coupling,
                  &g.low_first, &g.low_sign, &g.high_sign}) {
    v->assign(m * w, 0.0);
  }
  g.image.assign(3 * m * w, 0.0);
  for (auto* v : {&g.first_sign, &g.second_sign, &g.hw, &g.inverse_mass}) v->assign(n * w, 0.0);
  g.particle.assign(n * w, 0);
  // Kept for a new h (lanes stamped with their generations stay valid).
  g.memo_u.resize(3 * m * w);
  g.memo_r.resize(m * w);
  for (std::size_t lane = 0; lane < w; ++lane) {
    const RodChain& c = *chains[lane < count ? lane : 0];
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t i = k * w + lane;
      g.forward[i] = c.forward_[k];
      g.length[i] = c.length_[k];
      g.inverse_length[i] = c.inverse_length_[k];
      g.w_low[i] = c.w_low_[k];
      g.w_high[i] = c.w_high_[k];
      g.coupling[i] = c.coupling_[k];
      g.low_first[i] = c.low_first_[k];
      g.low_sign[i] = c.low_sign_[k];
      g.high_sign[i] = c.high_sign_[k];
      for (std::size_t a = 0; a < 3; ++a) g.image[(a * m + k) * w + lane] = c.image_[a * m + k];
    }
    for (std::size_t b = 0; b < n; ++b) {
      g.first_sign[b * w + lane] = c.first_sign_[b];
      g.second_sign[b * w + lane] = c.second_sign_[b];
      g.hw[b * w + lane] = h * c.bead_inverse_mass_[b];
      g.inverse_mass[b * w + lane] = c.bead_inverse_mass_[b];
      g.particle[b * w + lane] = c.bead_particle_[b];
    }
  }
  g.consecutive = g.particle[0];
  for (std::size_t b = 0; b < n; ++b) {
    for (std::size_t lane = 0; lane < w; ++lane) {
      if (g.particle[b * w + lane] != g.particle[0] + std::int64_t(lane * n + b))
        g.consecutive = -1;
    }
  }
  return g;
}

void RodChain::begin_across(const Vec3* q, const Box& box, std::size_t lane,
                            RodChainLanes::Group& group, RodChainLanes& lanes, bool same) const {
  constexpr std::size_t w = RodChainLanes::width;
  const std::size_t m = rows();
  // Directions of the impulses: the rods at the start of the step, fixed. Usually the last
  // projection's, already in the group's lane with the positions they were made at.
  const bool in_lane = group.memo_generation[lane] == memo_.generation;
  if (memo_.in_lanes && in_lane && same && memo_in(box)) return;
  const bool remembered = remembers(q, box);
  if (remembered && in_lane) return;
  if (!remembered) {
    RodChainWorkspace& ws = lanes.lane[lane];
    gather(q, ws.q);
    remember_directions(ws.q, q, box);
  }
  for (std::size_t k = 0; k < 3 * m; ++k) group.memo_u[k * w + lane] = memo_.u[k];
  for (std::size_t k = 0; k < m; ++k) group.memo_r[k * w + lane] = memo_.r[k];
  group.memo_generation[lane] = memo_.generation;
}

void RodChain::rewrap_across(const double* x, const Box& box, std::size_t lane,
                             RodChainLanes::Group& group, RodChainLanes::Across& across) const {
  constexpr std::size_t w = RodChainLanes::width;
  const std::size_t m = rows();
  const std::size_t n = beads();
  const Vec3& inverse_period = box.inverse_period();
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t a = forward_[k] > 0 ? k : k + 1;
    const std::size_t b = forward_[k] > 0 ? k + 1 : k;
    const Vec3 e = Vec3{x[a * w + lane], x[(n + a) * w + lane], x[(2 * n + a) * w + lane]} -
                   Vec3{x[b * w + lane], x[(n + b) * w + lane], x[(2 * n + b) * w + lane]};
    group.image[k * w + lane] = Box::round_to_integer(e.x * inverse_period.x);
    group.image[(m + k) * w + lane] = Box::round_to_integer(e.y * inverse_period.y);
    group.image[(2 * m + k) * w + lane] = Box::round_to_integer(e.z * inverse_period.z);
    const Vec3 image = box.minimum_image(e);
    across.u[k * w + lane] = image.x;
    across.u[(m + k) * w + lane] = image.y;
    across.u[(2 * m + k) * w + lane] = image.z;
    across.r[k * w + lane] = norm2(image);
  }
}

// solve_positions' iteration for all lanes at once, each lane's numbers its own; the per-lane
// decisions (held, converged, descended) as solve_positions takes them. The merit (the squared
// residual norm, Eigen's sum there) is summed in row order here: a decision it makes within
// rounding of the line search's bound sends the lane to solve_positions instead.
void RodChain::solve_positions_lanes(const RodChain* const* chains, std::size_t count,
                                     const Vec3* q, const Vec3* delta, double h, const Box& box,
                                     double tolerance, int max_iterations, RodChainLanes& lanes,
                                     Vec3* impulse, double* virial, SolverStatus* status,
                                     bool* solved) {
  constexpr std::size_t w = RodChainLanes::width;
  if (count == 0) return;
  const std::size_t m = chains[0]->rows();
  const std::size_t n = m + 1;
  RodChainLanes::Across& a = lanes.across;
  RodChainLanes::Group& g = group_of(chains, count, h, lanes);
  a.x0.resize(3 * n * w);
  a.x.resize(3 * n * w);
  a.impulse.resize(3 * n * w);
  a.u.resize(3 * m * w);
  a.r.resize(m * w);
  a.phi.resize(m * w);
  // z = 0, as solve_positions starts.
  a.z.assign(m * w, 0.0);
  size_lanes(m, lanes);
  // The free positions x0 = delta + q of every lane (lanes without a chain repeat the first
  // one: their results are never read).
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  // q against the positions the lanes' directions were made at, in the same pass.
  std::uint8_t same[w];
  const bool memo = g.memo_x.size() == a.x0.size();
  rod_passes::across::gather_sum(n, g.particle.data(), g.consecutive, &delta[0].x, &q[0].x,
                                 a.x0.data(), memo ? g.memo_x.data() : nullptr, same);
  for (std::size_t l = 0; l < count; ++l) {
    chains[l]->begin_across(q, box, l, g, lanes, same[l] != 0);
    status[l] = SolverStatus{};
    solved[l] = false;
  }
  for (std::size_t l = count; l < w; ++l) {
    for (auto* v : {&g.memo_u, &g.memo_r}) copy_lane(*v, 0, l);
  }
  const double* start_u = g.memo_u.data();
  const double* start_r = g.memo_r.data();
  const ImageRange range(box);
  enum class State : std::uint8_t { active, done, out };
  State state[w];
  for (std::size_t l = 0; l < w; ++l) state[l] = l < count ? State::active : State::out;
  double norm[w] = {}, merit[w] = {}, cap[w];
  std::uint8_t trying[w];
  // The residual at x for the trying lanes (held_or_residual, then try_trial's test of the
  // merit against cap; the first residual takes none). Made by rod_passes::across::measure_residual
  // or advance_and_measure: hold and bound, and the differences at x in a.u and a.r, or
  // (`normalized`) the directions, lengths and residual with their norm and merit too.
  std::uint8_t hold[w];
  double bound[w], made_norm[w], made_merit[w];
  auto evaluate = [&](const double* x, bool first, bool normalized) {
    bool rewrap = false;
    for (std::size_t l = 0; l < count; ++l) rewrap = rewrap || (trying[l] && !hold[l]);
    if (rewrap) {
      // The differences again, some rewrapped, then the rest pass by pass.
      rod_passes::across::differences(m, x, g.forward.data(), g.image.data(), range.periods,
                                      range.limit, a.u.data(), a.r.data(), hold);
      for (std::size_t l = 0; l < count; ++l) {
        if (trying[l] && !hold[l]) chains[l]->rewrap_across(x, box, l, g, a);
      }
      rod_passes::across::held_bound(m, a.r.data(), g.length.data(), g.inverse_length.data(),
                                     tolerance, bound);
      normalized = false;
    }
    // Whether x is within rounding of a finite `limit` (the estimate of the merit being off
    // by that: a relative 1e-10 is far above the rounding of a sum of a few hundred squares).
    auto unsure = [](double x, double limit) {
      return std::isfinite(limit) && std::abs(x - limit) <= 1e-10 * std::abs(limit);
    };
    bool residual = false;
    for (std::size_t l = 0; l < count; ++l) {
      if (!trying[l]) continue;
      const double held_merit = static_cast<double>(m) * bound[l] * bound[l] * 2;
      if (bound[l] <= tolerance && held_merit <= cap[l]) {
        if (unsure(held_merit, cap[l])) {
          state[l] = State::out;
        } else {
          state[l] = State::done;
          status[l].residual = bound[l];
        }
        trying[l] = 0;
        continue;
      }
      if (bound[l] <= tolerance && unsure(held_merit, cap[l])) {
        state[l] = State::out;
        trying[l] = 0;
        continue;
      }
      residual = true;
    }
    if (!residual) return;
    double* new_norm = made_norm;
    double* new_merit = made_merit;
    if (!normalized) {
      rod_passes::across::normalize_residual(m, a.u.data(), a.r.data(), g.length.data(),
                                             a.phi.data(), new_norm, new_merit);
    }
    for (std::size_t l = 0; l < count; ++l) {
      if (!trying[l]) continue;
      if (!first && (unsure(new_merit[l], cap[l]) || !(new_merit[l] <= cap[l]))) {
        state[l] = State::out;  // failed (solve_positions halves) or unsure
        continue;
      }
      norm[l] = new_norm[l];
      merit[l] = new_merit[l];
    }
  };
  for (std::size_t l = 0; l < w; ++l) {
    trying[l] = state[l] == State::active;
    cap[l] = std::numeric_limits<double>::infinity();
  }
  rod_passes::across::Measured measured{m,
                                        g.forward.data(),
                                        g.image.data(),
                                        range.periods,
                                        range.limit,
                                        g.length.data(),
                                        g.inverse_length.data(),
                                        tolerance,
                                        a.z.data(),
                                        lanes.x.data(),
                                        a.x0.data(),
                                        start_u,
                                        g.first_sign.data(),
                                        g.second_sign.data(),
                                        g.hw.data(),
                                        trying,
                                        a.impulse.data()};
  rod_passes::across::measure_residual(measured, a.x0.data(), a.u.data(), a.r.data(), hold, bound,
                                       a.phi.data(), made_norm, made_merit);
  evaluate(a.x0.data(), true, true);
  bool advanced = false;  // advance_and_measure made the positions (and impulses) of z
  for (int steps = 1;; ++steps) {
    bool any = false;
    for (std::size_t l = 0; l < count; ++l) {
      if (state[l] != State::active) continue;
      status[l].residual = norm[l];
      if (status[l].residual <= tolerance) {
        state[l] = State::done;
      } else if (status[l].iterations >= max_iterations) {
        state[l] = State::out;  // left to solve_positions (which gives up too)
      } else {
        ++status[l].iterations;
        any = true;
      }
    }
    if (!any) break;
    rod_passes::across::solve_bands(m, a.u.data(), start_u, g.w_low.data(), g.w_high.data(),
                                    g.coupling.data(), h, a.phi.data(), lanes.x.data(),
                                    lanes.c.data(), lanes.solved);
    for (std::size_t l = 0; l < w; ++l) {
      // A vanishing pivot: solve_positions redoes the chain.
      if (state[l] == State::active && !lanes.solved[l]) state[l] = State::out;
      trying[l] = state[l] == State::active;
      cap[l] = (1 - 1e-4 * 1.0) * merit[l];
    }
    // The residual made in the same pass after the first step, which (from the free positions'
    // O(h^2) residual) rarely holds the rods yet; after later steps only if the bound asks
    // for it. The same numbers either way.
    const bool residual_expected = steps == 1;
    advanced = true;
    rod_passes::across::advance_and_measure(measured, a.x.data(), a.u.data(), a.r.data(), hold,
                                            bound, residual_expected ? a.phi.data() : nullptr,
                                            made_norm, made_merit);
    evaluate(a.x.data(), false, residual_expected);
  }
  bool any_done = false;
  for (std::size_t l = 0; l < count; ++l) any_done = any_done || state[l] == State::done;
  if (!any_done) return;
  // The impulses of the multipliers z: made with the last positions (every lane's z as it
  // ended), else (no step taken) here.
  if (!advanced) {
    rod_passes::across::impulses(m, start_u, a.z.data(), g.first_sign.data(), g.second_sign.data(),
                                 a.impulse.data());
  }
  double virials[w];
  rod_passes::across::virial(m, a.z.data(), start_r, virials);
  std::uint8_t done[w] = {};
  for (std::size_t l = 0; l < count; ++l) {
    if (state[l] != State::done) continue;
    status[l].converged = true;
    virial[l] = virials[l];
    done[l] = 1;
    solved[l] = true;
  }
  rod_passes::across::scatter(n, g.particle.data(), g.consecutive, a.impulse.data(), done, false,
                              &impulse[0].x);
}

void RodChain::begin_momenta(const Vec3* x, const Vec3* p, const Box& box,
                             RodChainWorkspace& ws) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  ws.x.resize(3 * n);
  ws.v.resize(3 * n);
  for (std::size_t b = 0; b < n; ++b) {
    const std::int32_t g = bead_particle_[b];
    ws.x[b] = x[g].x;
    ws.x[n + b] = x[g].y;
    ws.x[2 * n + b] = x[g].z;
    const Vec3 v = p[g] * bead_inverse_mass_[b];
    ws.v[b] = v.x;
    ws.v[n + b] = v.y;
    ws.v[2 * n + b] = v.z;
  }
  // These positions start the next step unless the neighbour list wraps them meanwhile:
  // their directions are made where the next solve finds them.
  remember_directions(ws.x, x, box);
  // (C^T M^-1 C) mu = -C^T M^-1 p, C^T v summed over each rod's particles in their order.
  ws.pt.resize(static_cast<Eigen::Index>(m));
  rod_passes::projections(m, memo_.u.data(), ws.v.data(), low_first_.data(), low_sign_.data(),
                          high_sign_.data(), ws.pt.data());
}

void RodChain::finish_momenta(RodChainWorkspace& ws, Vec3* p, double& virial) const {
  const std::size_t n = beads();
  const std::size_t m = rows();
  bead_impulses(ws);
  for (std::size_t b = 0; b < n; ++b) {
    p[bead_particle_[b]] += Vec3{ws.impulse[b], ws.impulse[n + b], ws.impulse[2 * n + b]};
  }
  for (std::size_t k = 0; k < m; ++k) virial += ws.z(static_cast<Eigen::Index>(k)) * memo_.r[k];
}

bool RodChain::project_momenta(const Vec3* x, Vec3* p, const Box& box, RodChainWorkspace& ws,
                               double& virial) const {
  begin_momenta(x, p, box, ws);
  // Scale 1: multiplying by 1 leaves every entry as it is.
  if (!solve_coupled(memo_.u.data(), memo_.u.data(), 1.0, ws.pt, ws.z, ws)) return false;
  finish_momenta(ws, p, virial);
  return true;
}

void RodChain::remember_across(const Box& box, std::size_t lane, RodChainLanes::Group& group,
                               double largest) const {
  remember_box(box);
  memo_.in_lanes = true;
  memo_.largest_deviation = largest;
  group.memo_generation[lane] = memo_.generation;
}

// project_momenta for every lane at once (begin_momenta, the solve, finish_momenta), each
// lane's numbers its own.
void RodChain::project_momenta_lanes(const RodChain* const* chains, std::size_t count,
                                     const Vec3* x, Vec3* p, const Box& box, RodChainLanes& lanes,
                                     double* virial, bool* solved) {
  constexpr std::size_t w = RodChainLanes::width;
  if (count == 0) return;
  const std::size_t m = chains[0]->rows();
  const std::size_t n = m + 1;
  RodChainLanes::Across& a = lanes.across;
  // The constants the position solve left (its step h only sets hw, not read here).
  RodChainLanes::Group* found = find_group(chains, count, lanes);
  RodChainLanes::Group& g = found ? *found : group_of(chains, count, 0.0, lanes);
  a.x.resize(3 * n * w);
  a.v.resize(3 * n * w);
  a.impulse.resize(3 * n * w);
  a.u.resize(3 * m * w);
  a.r.resize(m * w);
  a.phi.resize(m * w);
  size_lanes(m, lanes);
  // Lanes without a chain repeat the first one.
  rod_passes::across::gather_velocities(n, g.particle.data(), g.consecutive, &x[0].x, &p[0].x,
                                        g.inverse_mass.data(), a.x.data(), a.v.data());
  // The directions at x (directions()), remembered where the next solve finds them.
  const ImageRange range(box);
  std::uint8_t hold[w];
  rod_passes::across::differences(m, a.x.data(), g.forward.data(), g.image.data(), range.periods,
                                  range.limit, a.u.data(), a.r.data(), hold);
  for (std::size_t l = 0; l < count; ++l) {
    if (!hold[l]) chains[l]->rewrap_across(a.x.data(), box, l, g, a);
  }
  // Their directions and lengths (directions()), remembered where the next solve finds them,
  // and (C^T M^-1 C) mu = -C^T M^-1 p.
  double largest[w];
  rod_passes::across::project_rows(
      m, a.u.data(), a.r.data(), g.length.data(), a.v.data(), g.low_first.data(), g.low_sign.data(),
      g.high_sign.data(), g.w_low.data(), g.w_high.data(), g.coupling.data(), largest,
      lanes.lower.data(), lanes.diagonal.data(), lanes.upper.data(), lanes.rhs.data());
  for (std::size_t l = 0; l < count; ++l) chains[l]->remember_across(box, l, g, largest[l]);
  eliminate_lanes(m, lanes);
  rod_passes::across::impulses(m, a.u.data(), lanes.x.data(), g.first_sign.data(),
                               g.second_sign.data(), a.impulse.data());
  double virials[w];
  rod_passes::across::virial(m, lanes.x.data(), a.r.data(), virials);
  std::uint8_t take[w] = {};
  for (std::size_t l = 0; l < count; ++l) {
    solved[l] = lanes.solved[l] != 0;
    if (!solved[l]) continue;
    take[l] = 1;
    virial[l] = virials[l];
  }
  rod_passes::across::scatter(n, g.particle.data(), g.consecutive, a.impulse.data(), take, true,
                              &p[0].x);
  // The directions and lengths, remembered in the group's lanes for the next step's solve,
  // with the positions they were made at.
  std::swap(a.u, g.memo_u);
  std::swap(a.r, g.memo_r);
  std::swap(a.x, g.memo_x);
}

double RodChain::largest_relative_deviation(const Vec3* x, const Box& box, RodChainWorkspace& ws,
                                            double start) const {
  const std::size_t m = rows();
  // The largest over the rods taken from 0, then with `start`: the same maximum (the
  // deviations are not negative; a NaN one is passed over either way).
  if (remembers(x, box)) return std::max(start, memo_.largest_deviation);
  gather(x, ws.x);
  ws.ux.resize(3 * m);
  ws.rx.resize(m);
  directions(ws.x.data(), box, ws.ux.data(), ws.rx.data());
  // gap_of's rod gap, norm(minimum_image(x_i - x_j)) - L: directions' length minus L.
  return std::max(start, largest_deviation(ws.rx.data()));
}

}  // namespace deli
