// The curvature term's dependence on the momenta, v.V''.v with v = M^-1 (p + alpha d):
// c(v0, v0) over every pair, and the cross and square terms in dv = M^-1 d from the Hessian
// blocks of the pairs that touch a particle d moves (the few rows of a contact).
#include "integrators/shadow_correction.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <utility>

#include "core/parallel.hpp"
#include "solvers/tridiagonal.hpp"

namespace deli {

std::optional<RodShadowTerms> rod_shadow_terms(const System& system,
                                               const std::vector<Constraint>& rods,
                                               const std::vector<Vec3>& force,
                                               std::vector<Vec3> projected_force) {
  const Particles& P = system.particles;
  const auto m = static_cast<Eigen::Index>(rods.size());
  std::vector<Vec3> grad(rods.size());
  for (std::size_t k = 0; k < rods.size(); ++k) {
    if (rods[k].kind != ConstraintKind::rod) return std::nullopt;
    grad[k] = system.box.minimum_image(P.position[rods[k].i] - P.position[rods[k].j]);
  }
  // (G G^T) mu = -G f_c: rods k and l couple where they share a particle.
  std::vector<std::vector<std::size_t>> rods_of(P.size());
  for (std::size_t k = 0; k < rods.size(); ++k) {
    rods_of[static_cast<std::size_t>(rods[k].i)].push_back(k);
    rods_of[static_cast<std::size_t>(rods[k].j)].push_back(k);
  }
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs(m);
  std::vector<std::size_t> coupled;
  for (std::size_t k = 0; k < rods.size(); ++k) {
    const Constraint& a = rods[k];
    const Vec3 fc_i = projected_force[a.i] - force[a.i];
    const Vec3 fc_j = projected_force[a.j] - force[a.j];
    rhs(static_cast<Eigen::Index>(k)) = -dot(grad[k], fc_i - fc_j);
    coupled = rods_of[static_cast<std::size_t>(a.i)];
    for (std::size_t l : rods_of[static_cast<std::size_t>(a.j)]) {
      if (std::find(coupled.begin(), coupled.end(), l) == coupled.end()) coupled.push_back(l);
    }
    for (std::size_t l : coupled) {
      const Constraint& b = rods[l];
      double sign = 0;
      sign += (a.i == b.i) - (a.i == b.j);
      sign -= (a.j == b.i) - (a.j == b.j);
      if (sign != 0) {
        entries.emplace_back(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(l),
                             sign * dot(grad[k], grad[l]));
      }
    }
  }
  Eigen::SparseMatrix<double> normal(m, m);
  normal.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd mu = solver.solve(rhs);
  RodShadowTerms terms;
  terms.projected_force = std::move(projected_force);
  terms.multiplier.assign(mu.data(), mu.data() + m);
  return terms;
}

std::optional<ShadowCorrection> shadow_correction_along(const ForceEngine& engine,
                                                        const System& system, double h,
                                                        const std::vector<Vec3>& p,
                                                        const std::vector<Vec3>& d,
                                                        const std::vector<Constraint>* rods,
                                                        const RodShadowTerms* rod_terms) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  const std::vector<Vec3>& force = rod_terms ? rod_terms->projected_force : engine.force();
  std::vector<Vec3> v(n);
  double force_term = 0;
  for (std::size_t i = 0; i < n; ++i) {
    v[i] = p[i] * (1.0 / P.mass[i]);
    force_term += norm2(force[i]) / P.mass[i];
  }
  double curvature = 0;
  if (!engine.force_field().pair_curvature(system, engine.neighbors(), v, curvature)) {
    return std::nullopt;
  }
  std::vector<Vec3> dv(n);
  if (!d.empty()) {
    for (std::size_t i = 0; i < n; ++i) dv[i] = d[i] * (1.0 / P.mass[i]);
  }
  double rod_cross = 0, rod_square = 0;
  if (rods && rod_terms) {
    for (std::size_t k = 0; k < rods->size(); ++k) {
      const Constraint& c = (*rods)[k];
      const double mu = rod_terms->multiplier[k];
      curvature += mu * norm2(v[c.i] - v[c.j]);
      rod_cross += mu * dot(dv[c.i] - dv[c.j], v[c.i] - v[c.j]);
      rod_square += mu * norm2(dv[c.i] - dv[c.j]);
    }
  }
  ShadowCorrection s;
  s.constant = -h * h / 24.0 * force_term + h * h / 12.0 * curvature;
  if (d.empty()) return s;
  std::vector<char> moved(n, 0);
  bool any = false;
  for (std::size_t i = 0; i < n; ++i) {
    moved[i] = d[i].x != 0 || d[i].y != 0 || d[i].z != 0;
    any = any || moved[i];
  }
  if (!any) return s;
  std::vector<PairHessian> blocks;
  if (!engine.force_field().pair_hessians(system, engine.neighbors(), moved, blocks)) {
    return std::nullopt;
  }
  double cross = 0, square = 0;
  for (const PairHessian& b : blocks) {
    const Vec3 u = dv[b.a] - dv[b.b];
    const Vec3 w = v[b.a] - v[b.b];
    const Eigen::Vector3d ue(u.x, u.y, u.z);
    const Eigen::Vector3d we(w.x, w.y, w.z);
    cross += ue.dot(b.block * we);
    square += ue.dot(b.block * ue);
  }
  // c(v + alpha dv) = c(v) + 2 alpha c(dv, v) + alpha^2 c(dv): the block is symmetric.
  s.linear = h * h / 12.0 * 2.0 * (cross + rod_cross);
  s.quadratic = h * h / 12.0 * (square + rod_square);
  return s;
}

std::optional<RodShadowTerms> projected_rod_terms(
    const ForceEngine& engine, const System& system, const std::vector<Constraint>& rods,
    const std::function<void(std::vector<Vec3>&)>& project) {
  // The projection is linear; it runs on the force scaled to order one (by a power of two,
  // exactly), so that its velocity tolerance means the same as for momenta however steep the
  // force.
  double largest = 0;
  for (const Vec3& f : engine.force()) largest = std::max(largest, norm(f));
  if (!(largest > 0)) {
    RodShadowTerms terms;
    terms.projected_force = engine.force();
    terms.multiplier.assign(rods.size(), 0.0);
    return terms;
  }
  int exponent = 0;
  std::frexp(largest, &exponent);
  std::vector<Vec3> projected = engine.force();
  for (Vec3& f : projected) f = f * std::ldexp(1.0, -exponent);
  project(projected);
  for (Vec3& f : projected) f = f * std::ldexp(1.0, exponent);
  return rod_shadow_terms(system, rods, engine.force(), std::move(projected));
}

std::optional<ShadowCorrection> shadow_correction_on_rods(
    const ForceEngine& engine, const System& system, double h, const std::vector<Vec3>& p,
    const std::vector<Vec3>& d, const std::vector<Constraint>& rods,
    const std::function<void(std::vector<Vec3>&)>& project) {
  if (rods.empty()) return shadow_correction_along(engine, system, h, p, d);
  double largest = 0;
  for (const Vec3& f : engine.force()) largest = std::max(largest, norm(f));
  if (!(largest > 0)) return shadow_correction_along(engine, system, h, p, d);
  const auto terms = projected_rod_terms(engine, system, rods, project);
  if (!terms) return std::nullopt;
  return shadow_correction_along(engine, system, h, p, d, &rods, &*terms);
}

namespace {

// The multipliers of (G M^-1 G^T) mu = G M^-1 F over rods numbered along their chains (every
// particle in at most two rods, and those two consecutive), where G M^-1 G^T is tridiagonal:
// solved in O(m) without assembling it. None where the rods are not so numbered or a pivot
// vanishes (then the sparse factorisation decides).
std::optional<Eigen::VectorXd> chain_multipliers(const Particles& P,
                                                 const std::vector<Constraint>& rods,
                                                 const std::vector<Vec3>& grad,
                                                 const Eigen::VectorXd& rhs) {
  const auto m = static_cast<Eigen::Index>(rods.size());
  std::vector<std::int32_t> first(P.size(), -1), second(P.size(), -1);
  for (std::size_t k = 0; k < rods.size(); ++k) {
    for (const std::int32_t s : {rods[k].i, rods[k].j}) {
      const auto at = static_cast<std::size_t>(s);
      if (first[at] < 0) {
        first[at] = static_cast<std::int32_t>(k);
      } else if (second[at] < 0 && static_cast<std::size_t>(first[at]) + 1 == k) {
        second[at] = static_cast<std::int32_t>(k);
      } else {
        return std::nullopt;
      }
    }
  }
  // Entry (k, l) as the sparse assembly makes it: sign_k sign_l / m_s grad_k . grad_l, over
  // the particles s the two rods share, summed in the order i, j of rod k.
  auto sign = [](const Constraint& c, std::size_t s) {
    return static_cast<std::size_t>(c.i) == s ? 1.0 : -1.0;
  };
  Tridiagonal a;
  a.resize_zero(m);
  for (std::size_t k = 0; k < rods.size(); ++k) {
    const Constraint& c = rods[k];
    const auto ai = static_cast<std::size_t>(c.i), aj = static_cast<std::size_t>(c.j);
    const double d = dot(grad[k], grad[k]);
    a.diagonal(static_cast<Eigen::Index>(k)) = 1.0 / P.mass[ai] * d + 1.0 / P.mass[aj] * d;
    if (k + 1 == rods.size()) continue;
    const Constraint& next = rods[k + 1];
    auto in_next = [&](std::size_t s) {
      return static_cast<std::size_t>(next.i) == s || static_cast<std::size_t>(next.j) == s;
    };
    if (in_next(ai) && in_next(aj)) return std::nullopt;  // two rods on one pair
    for (const std::size_t s : {ai, aj}) {
      if (!in_next(s)) continue;
      const double coupling = sign(c, s) * sign(next, s) / P.mass[s] * dot(grad[k], grad[k + 1]);
      a.upper(static_cast<Eigen::Index>(k)) = coupling;
      a.lower(static_cast<Eigen::Index>(k + 1)) = coupling;
    }
  }
  Eigen::VectorXd mu(m), scratch(m);
  if (!solve_tridiagonal(a, rhs, mu, scratch)) return std::nullopt;
  return mu;
}

}  // namespace

std::optional<double> verlet_shadow_energy_on_rods(const ForceEngine& engine, const System& system,
                                                   double h, const std::vector<Constraint>& rods) {
  if (!engine.last().tallied) return std::nullopt;
  const Particles& P = system.particles;
  const std::vector<Vec3>& force = engine.force();
  const auto m = static_cast<Eigen::Index>(rods.size());
  std::vector<Vec3> grad(rods.size());
  Eigen::VectorXd rhs(m);
  for (std::size_t k = 0; k < rods.size(); ++k) {
    const Constraint& c = rods[k];
    if (c.kind != ConstraintKind::rod) return std::nullopt;
    const auto ai = static_cast<std::size_t>(c.i), aj = static_cast<std::size_t>(c.j);
    grad[k] = system.box.minimum_image(P.position[ai] - P.position[aj]);
    rhs(static_cast<Eigen::Index>(k)) =
        dot(grad[k], force[ai] * (1.0 / P.mass[ai]) - force[aj] * (1.0 / P.mass[aj]));
  }
  std::optional<Eigen::VectorXd> multipliers = chain_multipliers(P, rods, grad, rhs);
  if (!multipliers) {
    // Row k of G M^-1 G^T: grad_k (1/m_i + 1/m_j) grad_k on the diagonal, +-grad_k / m_s
    // grad_l with a rod l sharing particle s.
    std::vector<std::vector<std::size_t>> rods_of(P.size());
    for (std::size_t k = 0; k < rods.size(); ++k) {
      rods_of[static_cast<std::size_t>(rods[k].i)].push_back(k);
      rods_of[static_cast<std::size_t>(rods[k].j)].push_back(k);
    }
    std::vector<Eigen::Triplet<double>> entries;
    for (std::size_t k = 0; k < rods.size(); ++k) {
      const Constraint& a = rods[k];
      const auto ai = static_cast<std::size_t>(a.i), aj = static_cast<std::size_t>(a.j);
      for (const auto& [s, sign_a] : {std::pair{ai, 1.0}, std::pair{aj, -1.0}}) {
        for (std::size_t l : rods_of[s]) {
          const Constraint& b = rods[l];
          const double sign_b = static_cast<std::size_t>(b.i) == s ? 1.0 : -1.0;
          entries.emplace_back(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(l),
                               sign_a * sign_b / P.mass[s] * dot(grad[k], grad[l]));
        }
      }
    }
    Eigen::SparseMatrix<double> normal(m, m);
    normal.setFromTriplets(entries.begin(), entries.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
    if (solver.info() != Eigen::Success) return std::nullopt;
    multipliers = solver.solve(rhs);
  }
  const Eigen::VectorXd& mu = *multipliers;
  std::vector<Vec3> projected = force;
  for (std::size_t k = 0; k < rods.size(); ++k) {
    const Vec3 along = grad[k] * mu(static_cast<Eigen::Index>(k));
    projected[static_cast<std::size_t>(rods[k].i)] -= along;
    projected[static_cast<std::size_t>(rods[k].j)] += along;
  }
  double curvature = 0;
  if (!engine.force_field().pair_curvature(system, engine.neighbors(), P.velocity, curvature)) {
    return std::nullopt;
  }
  for (std::size_t k = 0; k < rods.size(); ++k) {
    const Constraint& c = rods[k];
    curvature += mu(static_cast<Eigen::Index>(k)) * norm2(P.velocity[c.i] - P.velocity[c.j]);
  }
  const double kinetic = ordered_sum<double>(
      P.size(), [&](std::size_t i) { return 0.5 * P.mass[i] * norm2(P.velocity[i]); });
  const double force_term =
      ordered_sum<double>(P.size(), [&](std::size_t i) { return norm2(projected[i]) / P.mass[i]; });
  return verlet_modified_energy(kinetic, engine.last().potential, force_term, curvature, h);
}

}  // namespace deli
