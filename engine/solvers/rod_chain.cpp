#include "solvers/rod_chain.hpp"

#include <algorithm>
#include <cmath>

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
  return chain;
}

void RodChain::directions(const std::vector<Vec3>& x, const Box& box, std::vector<Vec3>& u,
                          std::vector<double>& r) const {
  const std::size_t m = rows();
  u.resize(m);
  r.resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 d = box.minimum_image(x[i_[k]] - x[j_[k]]);
    const double length = norm(d);
    r[k] = length;
    u[k] = length > 0 ? d * (1.0 / length) : Vec3{};
  }
}

// Entry by entry as ClusterRows::coupling_bands: each band entry starts at zero and takes its
// particles' terms (k.sign * l.sign * w) * a_k . b_l in particle order.
void RodChain::coupling_bands(const std::vector<Vec3>& a, const std::vector<Vec3>& b,
                              Tridiagonal& out) const {
  const auto m = static_cast<Eigen::Index>(rows());
  out.resize_zero(m);
  const double* w = inverse_mass_.data();
  for (Eigen::Index k = 0; k < m; ++k) {
    const double d = dot(a[k], b[k]);
    double diagonal = 0.0;
    diagonal += 1.0 * w[low_[k]] * d;
    diagonal += 1.0 * w[high_[k]] * d;
    out.diagonal(k) = diagonal;
    if (k + 1 < m) {
      const double s = shared_sign_[k] * w[shared_[k]];
      double upper = 0.0, lower = 0.0;
      upper += s * dot(a[k], b[k + 1]);
      lower += s * dot(a[k + 1], b[k]);
      out.upper(k) = upper;
      out.lower(k + 1) = lower;
    }
  }
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
  directions(ws.q, box, ws.uq, ws.rq);
  auto positions = [&](const Eigen::VectorXd& z, std::vector<Vec3>& x) {
    for (std::size_t p = 0; p < n; ++p) {
      x[p] = ws.x0[p] + impulse_on(p, ws.uq, z) * (h * inverse_mass_[p]);
    }
  };
  // Gaps (the residual) and the rods' directions and lengths at x.
  auto residual = [&](const std::vector<Vec3>& x, Eigen::VectorXd& phi, std::vector<Vec3>& u,
                      std::vector<double>& r) {
    directions(x, box, u, r);
    phi.resize(rows_count);
    for (std::size_t k = 0; k < m; ++k) phi(static_cast<Eigen::Index>(k)) = r[k] - length_[k];
  };

  status = SolverStatus{};
  ws.z.setZero(rows_count);
  // positions(z = 0): a zero impulse adds +0 to x0, which leaves it as it is.
  ws.x = ws.x0;
  residual(ws.x, ws.phi, ws.ux, ws.rx);
  for (;;) {
    status.residual = residual_norm(ws.phi);
    if (status.residual <= tolerance) {
      status.converged = true;
      break;
    }
    if (status.iterations >= max_iterations) return false;
    ++status.iterations;
    // d gap_k / d z_l = h grad g_k(x)^T M^-1 C_l(q).
    coupling_bands(ws.ux, ws.uq, ws.bands);
    ws.bands.lower *= h;
    ws.bands.diagonal *= h;
    ws.bands.upper *= h;
    ws.rhs = -ws.phi;
    if (!solve_tridiagonal(ws.bands, ws.rhs, ws.step, ws.pivots)) return false;
    const double merit = ws.phi.squaredNorm();
    double t = 1.0;
    for (int halvings = 0;; ++halvings) {
      ws.trial = ws.z + t * ws.step;
      positions(ws.trial, ws.xt);
      residual(ws.xt, ws.pt, ws.uxt, ws.rxt);
      if (ws.pt.squaredNorm() <= (1 - 1e-4 * t) * merit) {
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
  for (std::size_t p = 0; p < n; ++p) impulse[particles_[p]] = impulse_on(p, ws.uq, ws.z);
  for (std::size_t k = 0; k < m; ++k) virial += ws.z(static_cast<Eigen::Index>(k)) * ws.rq[k];
  return true;
}

bool RodChain::project_momenta(const Vec3* x, Vec3* p, const Box& box, RodChainWorkspace& ws,
                               double& virial) const {
  const std::size_t n = particles_.size();
  const std::size_t m = rows();
  ws.x.resize(n);
  ws.v.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::int32_t g = particles_[k];
    ws.x[k] = x[g];
    ws.v[k] = p[g] * inverse_mass_[k];
  }
  directions(ws.x, box, ws.ux, ws.rx);
  // (C^T M^-1 C) mu = -C^T M^-1 p, C^T v summed over each rod's particles in their order.
  ws.pt.resize(static_cast<Eigen::Index>(m));
  for (std::size_t k = 0; k < m; ++k) {
    double projected = 0.0;
    projected += low_sign_[k] * dot(ws.ux[k], ws.v[low_[k]]);
    projected += high_sign_[k] * dot(ws.ux[k], ws.v[high_[k]]);
    ws.pt(static_cast<Eigen::Index>(k)) = projected;
  }
  ws.rhs = -ws.pt;
  coupling_bands(ws.ux, ws.ux, ws.bands);
  if (!solve_tridiagonal(ws.bands, ws.rhs, ws.z, ws.pivots)) return false;
  for (std::size_t k = 0; k < n; ++k) p[particles_[k]] += impulse_on(k, ws.ux, ws.z);
  for (std::size_t k = 0; k < m; ++k) virial += ws.z(static_cast<Eigen::Index>(k)) * ws.rx[k];
  return true;
}

}  // namespace deli
