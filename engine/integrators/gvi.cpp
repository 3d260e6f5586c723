#include "integrators/gvi.hpp"

#include <algorithm>
#include <cmath>

#include "constraints/clusters.hpp"
#include "core/error.hpp"
#include "core/phase_timer.hpp"
#include "solvers/cluster_matrices.hpp"

namespace deli {

Gvi::Gvi(const ForceField& force_field, ConstraintSet constraints, const GviOptions& options,
         const Particles& particles)
    : ConstrainedIntegrator(force_field, std::move(constraints), options.timestep, options.skin,
                            options.reflection, options.energy, particles),
      feasibility_(options.feasibility),
      lagrangian_(options.lagrangian),
      reflections_(options.reflections),
      constrained_predictor_(options.constrained_predictor) {}

void Gvi::step(System& system, bool tally) {
  PhaseTimer& timer = phase_timer();
  const Phase outer = timer.enter(Phase::prediction);
  Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  const ConstraintTolerances& tol = constraints_.tolerances;
  std::vector<Vec3> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = P.velocity[i] * P.mass[i];
  step_virial_ = 0.0;

  // Displacement of the unconstrained forward step from (q, p): D1Ld(q, q + d) + p = 0.
  // Verlet: d = h M^-1 (p + h/2 F(q)). Midpoint: d = h M^-1 (p + h/2 F(q + d/2)), by fixed
  // point from the Verlet guess.
  auto free_displacement = [&](const std::vector<Vec3>& momenta) {
    const std::vector<Vec3>& f = engine_.force();
    std::vector<Vec3> d(n);
    for (std::size_t i = 0; i < n; ++i) d[i] = (momenta[i] + f[i] * (0.5 * h)) * (h / P.mass[i]);
    if (lagrangian_ == Lagrangian::midpoint) {
      std::vector<Vec3> mid(n), f_mid;
      for (int k = 0;; ++k) {
        for (std::size_t i = 0; i < n; ++i) mid[i] = P.position[i] + d[i] * 0.5;
        engine_.forces_at(system, mid, f_mid);
        double change = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
          const Vec3 next = (momenta[i] + f_mid[i] * (0.5 * h)) * (h / P.mass[i]);
          change = std::max(change, norm(next - d[i]));
          d[i] = next;
        }
        if (change <= constraints_.tolerances.solver) break;
        if (k == 200) midpoint_failure(system, change);
      }
    }
    return d;
  };
  auto moved = [&](const std::vector<Vec3>& d) {
    std::vector<Vec3> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = P.position[i] + d[i];
    return x;
  };
  // The predictor: the unconstrained step, or (predictor = "constrained") that step with
  // the equality rows (rods, strings) solved, which lands where the step will really go
  // when rods pull, so fewer contacts are missed.
  auto predict = [&](const std::vector<Vec3>& momenta) {
    const std::vector<Vec3> d = free_displacement(momenta);
    if (!constrained_predictor_ || constraints_.equalities.empty()) return moved(d);
    std::vector<Vec3> j(n);
    solve_positions(system, constraints_.equalities,
                    std::vector<bool>(constraints_.equalities.size(), true), P.position, d, j);
    std::vector<Vec3> x = moved(d);
    for (std::size_t i = 0; i < n; ++i) x[i] += j[i] * (h / P.mass[i]);
    return x;
  };
  std::vector<Vec3> predicted = moved(free_displacement(p));
  // Without pair forces or hard spheres no pair is ever looked up: any motion is fine.
  const bool pairs_matter = engine_.neighbors().cutoff() > 0;
  if (pairs_matter && !engine_.neighbors_cover(predicted)) {
    engine_.ensure_neighbors(system, true);
    predicted = moved(free_displacement(p));
    if (!engine_.neighbors_cover(predicted)) {
      throw SimulationError("step " + std::to_string(system.step + 1) +
                            ": a particle would move more than half the neighbour skin in one "
                            "step; increase [neighbor] skin or reduce the timestep");
    }
  }
  const std::vector<Vec3> q = P.position;
  const std::vector<Vec3> p_start = p;
  if (constrained_predictor_) predicted = predict(p);
  if (previous_positions_.size() != n) previous_positions_ = q;
  const Vec3* about = constraints_.linearized ? previous_positions_.data() : nullptr;

  // Candidate rows: those within reach of the largest displacement seen this step, found
  // once and refreshed only if a later displacement outgrows the reach.
  std::vector<Constraint> nearby;
  double reach = -1.0;
  auto candidates_for = [&](const std::vector<Vec3>& x) -> const std::vector<Constraint>& {
    double largest = 0.0;
    for (std::size_t i = 0; i < n; ++i) largest = std::max(largest, norm(x[i] - q[i]));
    if (2.0 * largest + tol.gap > reach) {
      reach = 4.0 * largest + 2.0 * tol.gap;
      nearby = constraints_.nearby_inequalities(P, q.data(), engine_.neighbors(), system.box, reach,
                                                about);
    }
    return nearby;
  };

  // Extended active set and reflection. A reflection can send a particle into a contact
  // the first prediction did not see: predict again from the reflected momenta until the
  // active set stops growing.
  timer.enter(Phase::active_set);
  std::vector<Constraint> active;
  for (int round = 0; round < 16; ++round) {
    bool grew = false;
    for (const Constraint& c : constraints_.active_among(candidates_for(predicted), q.data(),
                                                         predicted.data(), system.box)) {
      if (!contains(active, c)) active.push_back(c), grew = true;
    }
    if (!grew) break;
    if (!reflections_) break;
    std::vector<Constraint> rows = constraints_.equalities;
    rows.insert(rows.end(), active.begin(), active.end());
    {
      const TimedPhase reflecting(Phase::reflections);
      reflect_clusters(system, rows, constraints_.equalities.size(), q, p);
    }
    const TimedPhase predicting(Phase::prediction);
    predicted = predict(p);
  }
  stats_.active += static_cast<std::int64_t>(active.size());

  // Smooth set: active at q and tangent to the momenta after reflection.
  std::vector<Constraint> smooth;
  for (const Constraint& c : active) {
    const ConstraintValue v = evaluate(c, q.data(), system.box);
    if (std::abs(v.gap) > tol.gap) continue;
    if (std::abs(normal_velocity(c, v.u, p, P)) <= tol.velocity) smooth.push_back(c);
  }
  stats_.smooth += static_cast<std::int64_t>(smooth.size());

  // Position update, then the feasibility guard: inequality rows that would still end the
  // step overlapped join the complementarity set and the step is solved again.
  // Momenta before the new forces: half = p + h/2 F_start, positions q + h M^-1 (half +
  // impulse), with F_start = F(q) (Verlet) or F at the step's midpoint (midpoint, by fixed
  // point around the constrained solve).
  timer.enter(Phase::position_update);
  std::vector<Vec3> half(n), f_mid;
  auto displaced = [&](const std::vector<Vec3>& impulse) {
    std::vector<Vec3> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = q[i] + (half[i] + impulse[i]) * (h / P.mass[i]);
    return x;
  };
  std::vector<Vec3> impulse(n);
  double position_virial = 0.0;
  // DSI: no reflections; every row of the extended active set is a complementarity row.
  std::vector<Constraint> held = reflections_ ? smooth : active;
  std::vector<Constraint> landed;  // rows added by the guard this step
  std::vector<Constraint> equalities_and_held;
  auto position_update = [&]() {
    // The equality rows alone are passed as themselves: their clusters are prepared.
    if (!held.empty()) {
      equalities_and_held = constraints_.equalities;
      equalities_and_held.insert(equalities_and_held.end(), held.begin(), held.end());
    }
    const std::vector<Constraint>& rows =
        held.empty() ? constraints_.equalities : equalities_and_held;
    std::vector<bool> equality(rows.size(), false);
    std::fill_n(equality.begin(), constraints_.equalities.size(), true);
    const std::vector<Vec3>& f_start = engine_.force();
    for (std::size_t i = 0; i < n; ++i) half[i] = p[i] + f_start[i] * (0.5 * h);
    for (int k = 0;; ++k) {
      std::vector<Vec3> free(n);
      for (std::size_t i = 0; i < n; ++i) free[i] = half[i] * (h / P.mass[i]);
      std::fill(impulse.begin(), impulse.end(), Vec3{});
      if (!rows.empty())
        position_virial = solve_positions(system, rows, equality, q, free, impulse);
      if (lagrangian_ == Lagrangian::verlet) return;
      const std::vector<Vec3> x = displaced(impulse);
      std::vector<Vec3> mid(n);
      for (std::size_t i = 0; i < n; ++i) mid[i] = (q[i] + x[i]) * 0.5;
      engine_.forces_at(system, mid, f_mid);
      double change = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3 next = p[i] + f_mid[i] * (0.5 * h);
        change = std::max(change, norm(next - half[i]) * h / P.mass[i]);
        half[i] = next;
      }
      if (change <= constraints_.tolerances.solver && k > 0) return;
      if (k == 200) midpoint_failure(system, change);
    }
  };
  for (int round = 0;; ++round) {
    position_update();
    const std::vector<Vec3> x = displaced(impulse);
    std::vector<Constraint> violated;
    if (feasibility_ != Feasibility::none) {
      for (const Constraint& c :
           constraints_.active_among(candidates_for(x), q.data(), x.data(), system.box)) {
        if (evaluate(c, x.data(), system.box).gap < -tol.gap && !contains(held, c))
          violated.push_back(c);
      }
    }
    if (violated.empty() || round == 8) break;
    held.insert(held.end(), violated.begin(), violated.end());
    landed.insert(landed.end(), violated.begin(), violated.end());
  }
  stats_.fallbacks += static_cast<std::int64_t>(landed.size());

  // The energy to restore after a landing: H at the start of the step (the list is valid
  // at q, so this evaluation neither rebuilds nor wraps).
  double target_energy = 0.0;
  if (feasibility_ == Feasibility::restore && !landed.empty()) {
    const double potential =
        engine_.last().tallied ? engine_.last().potential : engine_.compute(system, true).potential;
    target_energy = potential;
    for (std::size_t i = 0; i < n; ++i) target_energy += 0.5 * norm2(p_start[i]) / P.mass[i];
  }

  timer.enter(Phase::momentum_update);
  // Momentum update: p + h/2 (F(q) + F(x)) + impulse, projected onto the equality rows and
  // the held rows still active at x (a landed row too, when the guard is inelastic).
  {
    const std::vector<Vec3> x = displaced(impulse);
    for (std::size_t i = 0; i < n; ++i) {
      P.position[i] = x[i];
      p[i] = half[i] + impulse[i];
    }
  }
  system.step += 1;
  system.time += h;
  engine_.compute(system, tally || (feasibility_ == Feasibility::restore && !landed.empty()));
  // The second half kick: F(x) for Verlet, the midpoint force again for midpoint.
  const std::vector<Vec3>& f = lagrangian_ == Lagrangian::verlet ? engine_.force() : f_mid;
  for (std::size_t i = 0; i < n; ++i) p[i] += f[i] * (0.5 * h);
  std::vector<Constraint> momentum_rows = constraints_.equalities;
  for (const Constraint& c : held) {
    const bool elastic_landing =
        (feasibility_ == Feasibility::reflect || feasibility_ == Feasibility::restore) &&
        contains(landed, c);
    if (!elastic_landing && std::abs(evaluate(c, P.position.data(), system.box).gap) <= tol.gap) {
      momentum_rows.push_back(c);
    }
  }
  if (momentum_rows.size() == constraints_.equalities.size()) {
    if (!momentum_rows.empty()) {
      step_virial_ += project_momenta(system, constraints_.equalities, P.position, p);
    }
  } else {
    step_virial_ += project_momenta(system, momentum_rows, P.position, p);
  }
  step_virial_ += position_virial;
  const bool elastic = feasibility_ == Feasibility::reflect || feasibility_ == Feasibility::restore;
  if (elastic && !landed.empty()) {
    // The landed rows now touch: reflect the momenta that still approach them, at x.
    std::vector<Constraint> rows = constraints_.equalities;
    rows.insert(rows.end(), landed.begin(), landed.end());
    const TimedPhase reflecting(Phase::reflections);
    reflect_clusters(system, rows, constraints_.equalities.size(), P.position, p);
  }
  if (feasibility_ == Feasibility::restore && !landed.empty()) {
    restore_energy(system, landed, target_energy, p);
  }
  for (std::size_t i = 0; i < n; ++i) P.velocity[i] = p[i] * (1.0 / P.mass[i]);
  ++stats_.steps;
  previous_positions_ = q;
  timer.enter(Phase::constraint_checks);
  // The rows that can have closed this step are among the candidates (their reach covers
  // the step's displacements): they decide overlaps; the exact minimum over every pair is
  // taken on thermo steps, where it is reported.
  candidates_for(P.position);
  record_geometry(system, nearby, tally);
  finish_step();
  timer.enter(outer);
}

void Gvi::restore_energy(System& system, const std::vector<Constraint>& landed, double target,
                         std::vector<Vec3>& p) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  // Direction: the sum of the landed rows' normals at x, projected onto the rod manifold's
  // cotangent space so that the momenta stay tangent to it.
  std::vector<Vec3> d(n);
  std::vector<Constraint> rows = constraints_.equalities;
  rows.insert(rows.end(), landed.begin(), landed.end());
  const auto first_landed = static_cast<std::int32_t>(constraints_.equalities.size());
  for (const Cluster& cluster : find_clusters(rows, n)) {
    if (cluster.rows.back() < first_landed) continue;
    const LocalCluster local = localize(cluster, rows, P.mass);
    std::vector<bool> equality;
    for (std::int32_t r : cluster.rows) equality.push_back(r < first_landed);
    const Eigen::MatrixXd N =
        projected_normals(local, equality, gather(P.position, cluster.particles), system.box);
    const std::vector<Vec3> sum = unflatten(N.rowwise().sum());
    for (std::size_t k = 0; k < cluster.particles.size(); ++k) d[cluster.particles[k]] += sum[k];
  }
  double kinetic = 0, a = 0, b = 0;
  for (std::size_t i = 0; i < n; ++i) {
    kinetic += 0.5 * norm2(p[i]) / P.mass[i];
    a += norm2(d[i]) / P.mass[i];
    b += dot(d[i], p[i]) / P.mass[i];
  }
  const double missing = target - (kinetic + engine_.last().potential);
  if (!(a > 0)) return;
  // K(p + alpha d) = K(p) + missing: a/2 alpha^2 + b alpha - missing = 0.
  const double discriminant = b * b + 2.0 * a * missing;
  double alpha;
  if (discriminant >= 0) {
    alpha = (-b + std::sqrt(discriminant)) / a;
  } else {
    alpha = -b / a;
    ++stats_.deficits;
  }
  for (std::size_t i = 0; i < n; ++i) p[i] += d[i] * alpha;
}

}  // namespace deli
