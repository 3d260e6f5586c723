#include "integrators/direct_substitution.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace deli {

DirectSubstitution::DirectSubstitution(const ForceField& force_field, ConstraintSet constraints,
                                       double timestep, double skin, const DirectOptions& options,
                                       const Particles& particles)
    : ConstrainedIntegrator(force_field, std::move(constraints), timestep, skin,
                            ReflectionOperator::generalized, ReflectionEnergy::hamiltonian,
                            particles),
      options_(options),
      constraint_force_(particles.size()) {
  if (options_.scheme != DirectScheme::midpoint) options_.alpha = 1.0;
  if (options_.scheme == DirectScheme::newmark && !(options_.beta > 0)) {
    throw InputError(
        "direct Newmark with beta = 0 applies no constraint force at the step's end, so it "
        "cannot keep any constraint: use beta > 0 or scheme = \"kane_imex\"");
  }
}

std::vector<Vec3> DirectSubstitution::land(System& system, const std::vector<Vec3>& q,
                                           const std::vector<Vec3>& y0,
                                           const std::vector<Constraint>& candidates,
                                           std::vector<Constraint>& held,
                                           std::vector<Vec3>& impulse, double& virial) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  const ConstraintTolerances& tol = constraints_.tolerances;
  std::vector<Vec3> y = y0;
  for (int round = 0;; ++round) {
    std::vector<Constraint> rows = constraints_.equalities;
    rows.insert(rows.end(), held.begin(), held.end());
    std::vector<bool> equality(rows.size(), false);
    std::fill_n(equality.begin(), constraints_.equalities.size(), true);
    std::fill(impulse.begin(), impulse.end(), Vec3{});
    y = y0;
    virial = 0.0;
    if (!rows.empty()) {
      // The KKT conditions want the gradients where the constraint is evaluated, at y itself:
      // solve with the gradients at the last y until y stops moving.
      std::vector<Vec3> at = q;
      for (int k = 0;; ++k) {
        std::vector<Vec3> delta(n);
        for (std::size_t i = 0; i < n; ++i) delta[i] = y0[i] - at[i];
        virial = solve_positions(system, rows, equality, at, delta, impulse);
        double change = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
          const Vec3 next = y0[i] + impulse[i] * (dt_ / P.mass[i]);
          change = std::max(change, norm(next - y[i]));
          y[i] = next;
        }
        if (k > 0 && change <= tol.solver) break;
        if (k == constraints_.limits.direct_settle_passes) {
          throw SimulationError("step " + std::to_string(system.step + 1) +
                                ": the direct method's constraint point did not settle (last "
                                "change " +
                                std::to_string(change) + " sigma after " + std::to_string(k) +
                                " passes, [constraints.limits] direct_settle_passes); reduce "
                                "the timestep");
        }
        at = y;
      }
    }
    std::vector<Constraint> violated;
    for (const Constraint& c : candidates) {
      if (evaluate(c, y.data(), system.box).gap < -tol.gap && !contains(held, c)) {
        violated.push_back(c);
      }
    }
    if (violated.empty()) return y;
    if (round == constraints_.limits.direct_landing_rounds) {
      throw SimulationError("step " + std::to_string(system.step + 1) +
                            ": the direct method found new overlaps after " +
                            std::to_string(round) + " rounds (" + std::to_string(violated.size()) +
                            " rows, first: atom " + std::to_string(P.id[violated.front().i]) +
                            ", gap " +
                            std::to_string(evaluate(violated.front(), y.data(), system.box).gap) +
                            " sigma; [constraints.limits] direct_landing_rounds); reduce the "
                            "timestep");
    }
    held.insert(held.end(), violated.begin(), violated.end());
  }
}

void DirectSubstitution::step(System& system, bool tally) {
  Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  const double alpha = options_.alpha;
  const bool newmark = options_.scheme != DirectScheme::midpoint;
  const double beta = options_.beta, gamma = options_.gamma;
  step_virial_ = 0.0;

  std::vector<Vec3> q = P.position;  // wrapped with the positions if the list is rebuilt
  const std::vector<Vec3> v = P.velocity;
  const std::vector<Vec3> f0 = engine_.force();
  // The implicit force: at the midpoint (midpoint) or the endpoint (Newmark, beta > 0).
  std::vector<Vec3> f_implicit = f0;
  auto free_end = [&]() {
    std::vector<Vec3> x(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double w = 1.0 / P.mass[i];
      if (!newmark) {
        x[i] = q[i] + (v[i] * P.mass[i] + f_implicit[i] * (0.5 * h)) * (h * w);
      } else {
        Vec3 previous = f0[i];
        if (options_.scheme == DirectScheme::newmark) previous += constraint_force_[i];
        x[i] = q[i] + v[i] * h +
               (previous * (1.0 - 2.0 * beta) + f_implicit[i] * (2.0 * beta)) * (0.5 * h * h * w);
      }
    }
    return x;
  };

  std::vector<Vec3> x_free = free_end();
  const std::vector<Constraint> candidates = candidates_for_step(system, q, x_free);

  std::vector<Constraint> held;
  std::vector<Vec3> impulse(n), x(n), y0(n);
  double virial = 0.0;
  iterate_midpoint(system, 1, [&] {
    x_free = free_end();
    for (std::size_t i = 0; i < n; ++i) y0[i] = q[i] + (x_free[i] - q[i]) * alpha;
    const std::vector<Vec3> y = land(system, q, y0, candidates, held, impulse, virial);
    double change = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 next = q[i] + (y[i] - q[i]) * (1.0 / alpha);
      change = std::max(change, norm(next - x[i]));
      x[i] = next;
    }
    // Without an implicit smooth force (Newmark with a force-free system, say) one pass is
    // exact; else iterate the force at the new midpoint or endpoint.
    std::vector<Vec3> at(n);
    for (std::size_t i = 0; i < n; ++i) at[i] = newmark ? x[i] : (q[i] + x[i]) * 0.5;
    engine_.forces_at(system, at, f_implicit);
    return change;
  });
  stats_.active += static_cast<std::int64_t>(held.size());

  // Momenta. The solver's impulse J moved the constraint point by h M^-1 J.
  for (std::size_t i = 0; i < n; ++i) P.position[i] = x[i];
  system.step += 1;
  system.time += h;
  engine_.compute(system, tally);
  double momentum_per_impulse;
  if (!newmark) {
    // p1 = 2/h M (q1 - q0) - p0: the constraint moved q1 by h M^-1 J / alpha.
    for (std::size_t i = 0; i < n; ++i) {
      P.velocity[i] = (x[i] - q[i]) * (2.0 / h) - v[i];
    }
    momentum_per_impulse = 2.0 / alpha;
  } else {
    // x = x_free + h M^-1 J = x_free + c h^2/2 M^-1 Fc1 with c = 2 beta (Newmark) or 1 (IMEX).
    const double c = options_.scheme == DirectScheme::newmark ? 2.0 * beta : 1.0;
    const double g = options_.scheme == DirectScheme::newmark ? gamma : 1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 fc1 = impulse[i] * (2.0 / (c * h));
      Vec3 previous = f0[i];
      if (options_.scheme == DirectScheme::newmark) previous += constraint_force_[i];
      P.velocity[i] = v[i] + (previous * (1.0 - gamma) + f_implicit[i] * gamma) * (h / P.mass[i]) +
                      fc1 * (g * h / P.mass[i]);
      constraint_force_[i] = fc1;
    }
    momentum_per_impulse = 2.0 * g / c;
  }
  step_virial_ = virial * momentum_per_impulse;
  ++stats_.steps;
  record_geometry(system, candidates, tally);
  finish_step();
}

std::vector<double> DirectSubstitution::saved_state() const {
  std::vector<double> out = ConstrainedIntegrator::saved_state();
  for (const Vec3& f : constraint_force_) out.insert(out.end(), {f.x, f.y, f.z});
  return out;
}

std::vector<double> DirectSubstitution::state_in_order(
    const std::vector<double>& state, const std::vector<std::int32_t>& order) const {
  // The base state, then the constraint force on each atom (as restore_state reads them).
  const std::size_t base = state.size() - 3 * order.size();
  std::vector<double> out = ConstrainedIntegrator::state_in_order(
      std::vector<double>(state.begin(), state.begin() + static_cast<std::ptrdiff_t>(base)), order);
  append_triples_in_order(state.data() + base, order, out);
  return out;
}

void DirectSubstitution::restore_state(const std::vector<double>& state, const System& system) {
  // The base state, then the constraint force on each atom.
  const std::size_t n = system.particles.size();
  if (state.size() < 3 * n) {
    throw InputError("the checkpoint's integrator state (" + std::to_string(state.size()) +
                     " numbers) is too short for '" + name() + "' with " + std::to_string(n) +
                     " atoms; restart with the input that wrote it");
  }
  ConstrainedIntegrator::restore_state({state.begin(), state.end() - 3 * n}, system);
  constraint_force_.clear();
  for (std::size_t i = state.size() - 3 * n; i < state.size(); i += 3) {
    constraint_force_.push_back({state[i], state[i + 1], state[i + 2]});
  }
}

}  // namespace deli
