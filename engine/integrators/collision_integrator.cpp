#include "integrators/collision_integrator.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "simulation/interrupt.hpp"

namespace deli {

CollisionIntegrator::CollisionIntegrator(const ForceField& force_field, ConstraintSet constraints,
                                         double timestep, double skin,
                                         const CollisionOptions& options,
                                         const Particles& particles)
    : ConstrainedIntegrator(force_field, std::move(constraints), timestep, skin,
                            ReflectionOperator::generalized, options.energy, particles),
      options_(options) {
  if (!constraints_.equalities.empty()) {
    throw InputError(
        "the collision integrator handles inequality constraints only (walls, hard spheres): "
        "remove the rods/anchors or use type = \"gvi\"");
  }
  if (constraints_.linearized) {
    throw InputError(
        "the collision integrator finds exact contact times: linearized = true "
        "has no meaning for it");
  }
}

std::vector<Vec3> CollisionIntegrator::free_positions(System& system, const std::vector<Vec3>& q,
                                                      const std::vector<Vec3>& p,
                                                      const std::vector<Vec3>& f, double tau,
                                                      std::vector<Vec3>* f_mid) const {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = q[i] + (p[i] + f[i] * (0.5 * tau)) * (tau / P.mass[i]);
  if (options_.base == Lagrangian::verlet) return x;
  std::vector<Vec3> mid(n), force;
  iterate_midpoint(system, 1, [&] {
    for (std::size_t i = 0; i < n; ++i) mid[i] = (q[i] + x[i]) * 0.5;
    engine_.forces_at(system, mid, force);
    double change = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 next = q[i] + (p[i] + force[i] * (0.5 * tau)) * (tau / P.mass[i]);
      change = std::max(change, norm(next - x[i]));
      x[i] = next;
    }
    return change;
  });
  if (f_mid) *f_mid = force;
  return x;
}

std::optional<double> CollisionIntegrator::contact_time(System& system, const Constraint& c,
                                                        const std::vector<Vec3>& q,
                                                        const std::vector<Vec3>& p,
                                                        const std::vector<Vec3>& f, double tau) {
  auto gap = [&](double t) {
    return evaluate(c, free_positions(system, q, p, f, t).data(), system.box).gap;
  };
  double hi = tau, g_hi = gap(hi);
  if (g_hi >= 0) return std::nullopt;
  // A feasible start: at q, or just after it when the row was reflected at q (gap ~ 0,
  // leaving). None: the row stays closed, a contact the event method cannot leave.
  double lo = 0.0, g_lo = gap(0.0);
  if (!(g_lo > 0)) {
    bool found = false;
    for (double t = 0.5 * hi; t > 1e-6 * hi; t *= 0.5) {
      const double g = gap(t);
      if (g > 0) {
        lo = t, g_lo = g, found = true;
        break;
      }
      hi = t, g_hi = g;
    }
    if (!found) return 0.0;
  }
  // Illinois false position on [lo, hi], gap(lo) > 0 >= gap(hi).
  int side = 0;
  int k = 0;
  for (; k < constraints_.limits.contact_time && hi - lo > options_.root_tolerance * dt_; ++k) {
    double t = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
    if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
    const double g = gap(t);
    if (g > 0) {
      lo = t, g_lo = g;
      if (side == 1) g_hi *= 0.5;
      side = 1;
    } else {
      hi = t, g_hi = g;
      if (side == -1) g_lo *= 0.5;
      side = -1;
    }
  }
  if (hi - lo > options_.root_tolerance * dt_) ++stats_.contact_time_caps;
  return lo;
}

void CollisionIntegrator::step(System& system, bool tally) {
  Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  const ConstraintTolerances& tol = constraints_.tolerances;
  step_virial_ = 0.0;
  std::vector<Vec3> q = P.position, p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = P.velocity[i] * P.mass[i];
  std::vector<Vec3> f = engine_.force();

  std::vector<Vec3> x_full = free_positions(system, q, p, f, h);
  const std::vector<Constraint> candidates = candidates_for_step(system, q, x_full);

  // Advances (q, p) by an unconstrained step of length tau; f becomes the force at the end.
  auto advance = [&](double tau) {
    std::vector<Vec3> f_mid;
    const std::vector<Vec3> x = free_positions(system, q, p, f, tau, &f_mid);
    std::vector<Vec3> f_end;
    engine_.forces_at(system, x, f_end);
    for (std::size_t i = 0; i < n; ++i) {
      p[i] +=
          options_.base == Lagrangian::verlet ? (f[i] + f_end[i]) * (0.5 * tau) : f_mid[i] * tau;
    }
    q = x;
    f = f_end;
  };

  double remaining = h;
  int events = 0;
  while (true) {
    double first = remaining;
    std::vector<Constraint> hit;
    for (const Constraint& c : candidates) {
      const std::optional<double> t = contact_time(system, c, q, p, f, remaining);
      if (!t) continue;
      if (*t < first) first = *t, hit.clear();
      if (*t <= first) hit.push_back(c);
    }
    if (hit.empty()) {
      advance(remaining);
      break;
    }
    if (interrupt_requested()) {
      throw SimulationError("interrupted during step " + std::to_string(system.step + 1) +
                            ", which had not ended after " + std::to_string(events) +
                            " contact events (a persistent contact, which an event-driven "
                            "method cannot resolve): no checkpoint of an unfinished step; "
                            "lower max_events_per_step or use type = \"gvi\"");
    }
    if (++events > options_.max_events_per_step) {
      throw SimulationError(
          "step " + std::to_string(system.step + 1) + ": the collision integrator met more than " +
          std::to_string(options_.max_events_per_step) +
          " contact events in one step (a persistent contact, which an event-driven method "
          "cannot resolve); use type = \"gvi\"");
    }
    advance(first);
    remaining -= first;
    // Reflect off the rows that hit now and any other row touching here.
    std::vector<Constraint> rows = hit;
    for (const Constraint& c : candidates) {
      if (!contains(rows, c) && evaluate(c, q.data(), system.box).gap <= tol.gap) rows.push_back(c);
    }
    stats_.active += static_cast<std::int64_t>(hit.size());
    P.position = q;  // the shadow energy's Hessian is taken at the system's positions
    reflect_clusters(system, rows, 0, q, p);
  }

  for (std::size_t i = 0; i < n; ++i) {
    P.position[i] = q[i];
    P.velocity[i] = p[i] * (1.0 / P.mass[i]);
  }
  system.step += 1;
  system.time += h;
  engine_.compute(system, tally);
  ++stats_.steps;
  record_geometry(system, candidates, tally);
  finish_step();
}

}  // namespace deli
