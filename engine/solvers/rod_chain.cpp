#include "solvers/rod_chain.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "solvers/tridiagonal.hpp"

namespace deli {

std::unique_ptr<RodChain> RodChain::make(const LocalCluster& cluster) {
  const std::size_t m = cluster.rows.size();
  const std::size_t n = cluster.size();
  if (m == 0) return nullptr;
  std::unique_ptr<RodChain> chain(new RodChain());
  RodChain& c = *chain;
  c.particles_ = cluster.particles;
  c.inverse_mass_ = cluster.inverse_mass;
  c.first_row_.assign(n, -1);
  c.second_row_.assign(n, -1);
  c.first_sign_.assign(n, 0.0);
  c.second_sign_.assign(n, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    const Constraint& row = cluster.rows[k];
    if (row.kind != ConstraintKind::rod || row.i < 0 || row.j < 0 || row.i == row.j) return nullptr;
    c.i_.push_back(row.i);
    c.j_.push_back(row.j);
    c.length_.push_back(row.length);
    c.inverse_length_.push_back(1.0 / row.length);
    const bool i_first = row.i < row.j;
    c.low_.push_back(i_first ? row.i : row.j);
    c.high_.push_back(i_first ? row.j : row.i);
    c.low_sign_.push_back(i_first ? 1.0 : -1.0);
    c.high_sign_.push_back(i_first ? -1.0 : 1.0);
    for (const auto& [p, sign] : {std::pair{row.i, 1.0}, std::pair{row.j, -1.0}}) {
      if (c.first_row_[p] < 0) {
        c.first_row_[p] = static_cast<std::int32_t>(k);
        c.first_sign_[p] = sign;
      } else if (c.second_row_[p] < 0 && c.first_row_[p] + 1 == static_cast<std::int32_t>(k)) {
        c.second_row_[p] = static_cast<std::int32_t>(k);
        c.second_sign_[p] = sign;
      } else {
        return nullptr;  // a third rod on a particle, or two rods not consecutive
      }
    }
  }
  // Consecutive rods share exactly one particle.
  c.shared_.assign(m, -1);
  c.shared_sign_.assign(m, 0.0);
  for (std::size_t k = 0; k + 1 < m; ++k) {
    int shared = 0;
    for (std::int32_t p : {c.i_[k], c.j_[k]}) {
      if (c.second_row_[p] == static_cast<std::int32_t>(k + 1)) {
        ++shared;
        c.shared_[k] = p;
        c.shared_sign_[k] = c.first_sign_[p] * c.second_sign_[p];
      }
    }
    if (shared != 1) return nullptr;
  }
  for (std::size_t p = 0; p < n; ++p) {
    if (c.first_row_[p] < 0) return nullptr;  // a particle no rod touches
  }
  c.image_.assign(m, Vec3{});
  return chain;
}

void RodChain::directions(const std::vector<Vec3>& x, const Box& box, std::vector<Vec3>& u,
                          std::vector<double>& r) const {
  differences(x, box, u, r);
  normalize(u, r);
}

// Three passes (here the first, normalize the other two), so that the square roots and the
// divisions of successive rods overlap (within one rod each waits for the last); the same
// operations as norm() and d / |d|. The minimum image with each rod's last periodic image n:
// d - period n is Box::minimum_image(d), operation for operation, whenever rounding
// d / period would give n, as it does when |d - period n| <= 0.4 period on every periodic
// axis (d / period within 0.4 of n, and the rounding of the division far below 0.1). Only
// when a rod leaves that range (a particle was wrapped, or a first call) is the image
// rounded anew, for the whole pass: a branch and six operations per rod instead of the
// roundings' conversions.
void RodChain::differences(const std::vector<Vec3>& x, const Box& box, std::vector<Vec3>& d,
                           std::vector<double>& d2) const {
  const std::size_t m = rows();
  d.resize(m);
  d2.resize(m);
  const Vec3 period = box.period();  // a copy: d's stores cannot alias it
  constexpr double open = std::numeric_limits<double>::infinity();
  const Vec3 limit{period.x > 0 ? 0.4 * period.x : open, period.y > 0 ? 0.4 * period.y : open,
                   period.z > 0 ? 0.4 * period.z : open};
  const Vec3* image = image_.data();
  bool images_hold = true;
  for (std::size_t k = 0; k < m; ++k) {
    Vec3 e = x[i_[k]] - x[j_[k]];
    e.x -= period.x * image[k].x;
    e.y -= period.y * image[k].y;
    e.z -= period.z * image[k].z;
    // Also false for NaN. Bitwise: no branch per rod.
    const int within = static_cast<int>(std::abs(e.x) <= limit.x) &
                       static_cast<int>(std::abs(e.y) <= limit.y) &
                       static_cast<int>(std::abs(e.z) <= limit.z);
    images_hold &= within != 0;
    d[k] = e;
    d2[k] = norm2(e);
  }
  if (images_hold) return;
  const Vec3& inverse_period = box.inverse_period();
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 e = x[i_[k]] - x[j_[k]];
    image_[k] = {Box::round_to_integer(e.x * inverse_period.x),
                 Box::round_to_integer(e.y * inverse_period.y),
                 Box::round_to_integer(e.z * inverse_period.z)};
    d[k] = box.minimum_image(e);
    d2[k] = norm2(d[k]);
  }
}

void RodChain::normalize(std::vector<Vec3>& u, std::vector<double>& r) const {
  const std::size_t m = rows();
  for (std::size_t k = 0; k < m; ++k) r[k] = std::sqrt(r[k]);
  for (std::size_t k = 0; k < m; ++k) u[k] = r[k] > 0 ? u[k] * (1.0 / r[k]) : Vec3{};
}

// The residual r_k - L_k with r_k = fl(sqrt(d2_k)) obeys, for d2_k within a quarter of L_k^2
// (so that d2_k - fl(L_k^2) and r_k - L_k are exact subtractions, Sterbenz):
//   |r_k - L_k| <= |sqrt(d2_k) - L_k| + |r_k - sqrt(d2_k)|
//              <= (|fl(d2_k - fl(L_k^2))| + L_k^2 2^-53) / L_k + sqrt(d2_k) 2^-53
//              <= fl(|d2_k - fl(L_k^2)| fl(1 / L_k)) (1 + 2^-51) + L_k 2^-51,
// as |sqrt(d2) - L| = |d2 - L^2| / (sqrt(d2) + L) <= |d2 - L^2| / L. The bound below rounds
// with slack 2^-50 on both terms, above all rounding of its own evaluation.
double RodChain::held_bound(const std::vector<double>& d2, double tolerance) const {
  constexpr double slack = 0x1p-50;
  double bound = 0.0;
  for (std::size_t k = 0; k < rows(); ++k) {
    const double length = length_[k];
    const double relative_gap = std::abs(d2[k] - length * length) * inverse_length_[k];
    const double rod_bound = relative_gap * (1 + slack) + length * slack;
    // Also false for NaN.
    if (!(relative_gap <= 0.25 * length && rod_bound <= tolerance)) {
      return std::numeric_limits<double>::infinity();
    }
    bound = std::max(bound, rod_bound);
  }
  return bound;
}

// solve_tridiagonal's elimination with each band entry made as ClusterRows::coupling_bands
// makes it (starting at zero, its particles' terms (k.sign * l.sign * w) * a_k . b_l in
// particle order), then scaled, as it is needed: the same operations in the same order,
// without storing the bands.
bool RodChain::solve_coupled(const std::vector<Vec3>& a, const std::vector<Vec3>& b, double scale,
                             const Eigen::VectorXd& minus_rhs, Eigen::VectorXd& x,
                             Eigen::VectorXd& c) const {
  const auto m = static_cast<Eigen::Index>(rows());
  x.resize(m);
  c.resize(m);
  const double* w = inverse_mass_.data();
  auto diagonal = [&](Eigen::Index k) {
    const double d = dot(a[k], b[k]);
    double entry = 0.0;
    entry += 1.0 * w[low_[k]] * d;
    entry += 1.0 * w[high_[k]] * d;
    return entry * scale;
  };
  // A(k, k+1) and A(k, k-1).
  auto upper = [&](Eigen::Index k) {
    double entry = 0.0;
    entry += shared_sign_[k] * w[shared_[k]] * dot(a[k], b[k + 1]);
    return entry * scale;
  };
  auto lower = [&](Eigen::Index k) {
    double entry = 0.0;
    entry += shared_sign_[k - 1] * w[shared_[k - 1]] * dot(a[k], b[k - 1]);
    return entry * scale;
  };
  auto rhs = [&](Eigen::Index k) { return -minus_rhs(k); };
  return solve_tridiagonal_twisted(m, lower, diagonal, upper, rhs, x.data(), c.data());
}

bool RodChain::remembered_at(const std::vector<Vec3>& x, const Box& box) const {
  const DirectionsMemo& memo = memo_;
  return memo.valid && memo.period.x == box.period().x && memo.period.y == box.period().y &&
         memo.period.z == box.period().z && memo.inverse_period.x == box.inverse_period().x &&
         memo.inverse_period.y == box.inverse_period().y &&
         memo.inverse_period.z == box.inverse_period().z && memo.x.size() == x.size() &&
         std::memcmp(memo.x.data(), x.data(), x.size() * sizeof(Vec3)) == 0;
}

void RodChain::start_directions(const std::vector<Vec3>& q, const Box& box) const {
  if (!remembered_at(q, box)) remember_directions(q, box);
}

void RodChain::remember_directions(const std::vector<Vec3>& x, const Box& box) const {
  directions(x, box, memo_.u, memo_.r);
  memo_.x = x;
  memo_.period = box.period();
  memo_.inverse_period = box.inverse_period();
  memo_.valid = true;
}

bool RodChain::solve_positions(const Vec3* q, const Vec3* delta, double h, const Box& box,
                               double tolerance, int max_iterations, int line_search_limit,
                               RodChainWorkspace& ws, Vec3* impulse, double& virial,
                               SolverStatus& status) const {
  const std::size_t n = particles_.size();
  const std::size_t m = rows();
  const auto rows_count = static_cast<Eigen::Index>(m);
  ws.q.resize(n);
  ws.x0.resize(n);
  ws.x.resize(n);
  ws.xt.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    const std::int32_t g = particles_[p];
    ws.q[p] = q[g];
    ws.x0[p] = delta[g] + q[g];
  }
  // Directions of the impulses: the rods at the start of the step, fixed.
  start_directions(ws.q, box);
  const std::vector<Vec3>& uq = memo_.u;
  const std::vector<double>& rq = memo_.r;
  auto positions = [&](const Eigen::VectorXd& z, std::vector<Vec3>& x) {
    for (std::size_t p = 0; p < n; ++p) {
      x[p] = ws.x0[p] + impulse_on(p, uq, z) * (h * inverse_mass_[p]);
    }
  };

  // Whether the rods at x, whose differences and squared lengths u, r hold, are proven held
  // (with the residual's norm below `merit_cap` too) without their square roots: the
  // residual, then computed, would show it, so the iteration would take the same course.
  // Otherwise u, r, phi become the directions, lengths and residual at x. At the last
  // position of a solve this saves the square roots and divisions of one directions pass.
  auto held_or_residual = [&](Eigen::VectorXd& phi, std::vector<Vec3>& u, std::vector<double>& r,
                              double merit_cap) {
    const double bound = held_bound(r, tolerance);
    // sum_k phi_k^2 <= m bound^2; the factor 2 covers the rounding of Eigen's sum.
    if (bound <= tolerance && static_cast<double>(m) * bound * bound * 2 <= merit_cap) {
      status.residual = bound;
      return true;
    }
    normalize(u, r);
    phi.resize(rows_count);
    for (std::size_t k = 0; k < m; ++k) phi(static_cast<Eigen::Index>(k)) = r[k] - length_[k];
    return false;
  };

  status = SolverStatus{};
  ws.z.setZero(rows_count);
  // positions(z = 0): a zero impulse adds +0 to x0, which leaves it as it is.
  ws.x = ws.x0;
  differences(ws.x, box, ws.ux, ws.rx);
  bool held = held_or_residual(ws.phi, ws.ux, ws.rx, std::numeric_limits<double>::infinity());
  while (!held) {
    status.residual = residual_norm(ws.phi);
    if (status.residual <= tolerance) {
      status.converged = true;
      break;
    }
    if (status.iterations >= max_iterations) return false;
    ++status.iterations;
    // d gap_k / d z_l = h grad g_k(x)^T M^-1 C_l(q).
    if (!solve_coupled(ws.ux, uq, h, ws.phi, ws.step, ws.pivots)) return false;
    const double merit = ws.phi.squaredNorm();
    double t = 1.0;
    for (int halvings = 0;; ++halvings) {
      ws.trial = ws.z + t * ws.step;
      positions(ws.trial, ws.xt);
      const double merit_cap = (1 - 1e-4 * t) * merit;
      differences(ws.xt, box, ws.uxt, ws.rxt);
      if (held_or_residual(ws.pt, ws.uxt, ws.rxt, merit_cap)) {
        std::swap(ws.z, ws.trial);
        std::swap(ws.x, ws.xt);
        held = true;
        break;
      }
      if (ws.pt.squaredNorm() <= merit_cap) {
        std::swap(ws.z, ws.trial);
        std::swap(ws.x, ws.xt);
        std::swap(ws.phi, ws.pt);
        std::swap(ws.ux, ws.uxt);
        std::swap(ws.rx, ws.rxt);
        break;
      }
      if (halvings == line_search_limit) return false;  // no decrease: the generic path reports
      t *= 0.5;
    }
  }
  status.converged = true;
  for (std::size_t p = 0; p < n; ++p) impulse[particles_[p]] = impulse_on(p, uq, ws.z);
  for (std::size_t k = 0; k < m; ++k) virial += ws.z(static_cast<Eigen::Index>(k)) * rq[k];
  return true;
}

bool RodChain::project_momenta(const Vec3* x, Vec3* p, const Box& box, RodChainWorkspace& ws,
                               double* virial_terms) const {
  const std::size_t n = particles_.size();
  const std::size_t m = rows();
  ws.x.resize(n);
  ws.v.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::int32_t g = particles_[k];
    ws.x[k] = x[g];
    ws.v[k] = p[g] * inverse_mass_[k];
  }
  // These positions start the next step unless the neighbour list wraps them meanwhile:
  // their directions are made where the next solve finds them.
  remember_directions(ws.x, box);
  const std::vector<Vec3>& ux = memo_.u;
  const std::vector<double>& rx = memo_.r;
  // (C^T M^-1 C) mu = -C^T M^-1 p, C^T v summed over each rod's particles in their order.
  ws.pt.resize(static_cast<Eigen::Index>(m));
  for (std::size_t k = 0; k < m; ++k) {
    double projected = 0.0;
    projected += low_sign_[k] * dot(ux[k], ws.v[low_[k]]);
    projected += high_sign_[k] * dot(ux[k], ws.v[high_[k]]);
    ws.pt(static_cast<Eigen::Index>(k)) = projected;
  }
  // Scale 1: multiplying by 1 leaves every entry as it is.
  if (!solve_coupled(ux, ux, 1.0, ws.pt, ws.z, ws.pivots)) return false;
  for (std::size_t k = 0; k < n; ++k) p[particles_[k]] += impulse_on(k, ux, ws.z);
  for (std::size_t k = 0; k < m; ++k) virial_terms[k] = ws.z(static_cast<Eigen::Index>(k)) * rx[k];
  return true;
}

double RodChain::largest_relative_deviation(const Vec3* x, const Box& box, RodChainWorkspace& ws,
                                            double start) const {
  const std::size_t n = particles_.size();
  ws.x.resize(n);
  for (std::size_t k = 0; k < n; ++k) ws.x[k] = x[particles_[k]];
  const std::vector<double>* r = &memo_.r;
  if (!remembered_at(ws.x, box)) {
    directions(ws.x, box, ws.ux, ws.rx);
    r = &ws.rx;
  }
  // gap_of's rod gap, norm(minimum_image(x_i - x_j)) - L: directions' length minus L.
  double largest = start;
  for (std::size_t k = 0; k < rows(); ++k) {
    largest = std::max(largest, std::abs((*r)[k] - length_[k]) / length_[k]);
  }
  return largest;
}

}  // namespace deli
