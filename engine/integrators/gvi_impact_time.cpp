// GVI's step with contact = "impact_time": Verlet's half kick, the exact hard-sphere and
// wall flow over the whole step (ImpactTimeDrift), Verlet's second half kick; on a step with
// a contact under a force, the energy of the step's start given back along the normals of
// the rows that touched. Why and what it keeps: README, "Contact treatment".
#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/phase_timer.hpp"
#include "integrators/contact_group.hpp"
#include "integrators/gvi.hpp"
#include "integrators/shadow_correction.hpp"
#include "integrators/shadow_remainder.hpp"

namespace deli {

void Gvi::refuse_impact_times_unless_supported() const {
  if (constraints_.linearized) {
    throw InputError(
        "[integrator] contact = \"impact_time\" finds exact contact times: linearized = true has "
        "no meaning for it");
  }
  if (lagrangian_ != Lagrangian::verlet || !reflections_) {
    throw InputError(
        "[integrator] contact = \"impact_time\" is a Verlet splitting of GVI: use type = "
        "\"gvi\", lagrangian = \"verlet\"");
  }
  const auto string =
      std::find_if(constraints_.equalities.begin(), constraints_.equalities.end(),
                   [](const Constraint& c) { return c.kind != ConstraintKind::rod; });
  if (shadow_remainder_steps_ > 0 && string != constraints_.equalities.end()) {
    throw InputError(
        "[integrator] shadow_remainder_steps: the modified energy has no string terms (atom " +
        std::to_string(string->i + 1) +
        " is held on a string); remove the key (strings restore S alone)");
  }
}

std::optional<double> Gvi::start_shadow_energy(System& system, double start) {
  const auto s = shadow_correction_on_rods(engine_, system, dt_, ws_.p_start, {},
                                           constraints_.equalities, [&](std::vector<Vec3>& force) {
                                             project_momenta(system, constraints_.equalities,
                                                             system.particles.position, force);
                                           });
  if (!s) return std::nullopt;
  return start + s->constant;
}

void Gvi::drift_with_covering_rows(System& system, bool pairs_matter,
                                   const std::function<DriftSpan()>& drift_once) {
  const double gap_tolerance = constraints_.tolerances.gap;
  for (int attempt = 0;; ++attempt) {
    const DriftSpan span = drift_once();
    bool covered = !pairs_matter || engine_.neighbors_cover(*span.end);
    for (const std::vector<Vec3>& at : *span.vertices)
      covered = covered && (!pairs_matter || engine_.neighbors_cover(at));
    const bool reached = 2.0 * span.longest + gap_tolerance <= ws_.reach;
    if (covered && reached) return;
    if (attempt == 2) {
      throw SimulationError("step " + std::to_string(system.step + 1) +
                            ": a particle would move more than half the neighbour skin in one "
                            "step; increase [neighbor] skin or reduce the timestep");
    }
    if (!covered) {
      // Rebuilding wraps the positions: the step starts again from them.
      engine_.ensure_neighbors(system, true);
      ws_.q = system.particles.position;
    }
    ws_.reach = 4.0 * span.longest + 2.0 * gap_tolerance;
    nearby_rows_.collect(constraints_, system.particles, ws_.q.data(), engine_.neighbors(),
                         system.box, ws_.reach, nullptr, gap_tolerance, ws_.nearby,
                         ws_.nearby_gap_at_q);
    ws_.candidates.assign(ws_.nearby, ws_.nearby_gap_at_q);
  }
}

// S given back on a contact step still loses R(start) - R(end) of the modified energy
// (shadow_remainder.hpp): the target becomes S(start) + R(start) - R(end), R read over the
// touched rows' particles and the rod clusters they belong to, before the step (back in time
// from its start) and after it; p are the momenta at the step's end.
void Gvi::restore_shadow_remainder(System& system, const std::vector<Constraint>& touched,
                                   double target, double shadow_target, std::vector<Vec3>& p) {
  const std::size_t n = system.particles.size();
  const std::vector<Constraint>& rods = constraints_.equalities;
  const std::vector<char> moving = contact_group(touched, rods, n);
  // The virtual steps' solves are not the run's: its statistics and virial stay as they were.
  const ConstraintStatistics counted = stats_;
  // RATTLE's stages on the rods. solve_positions scales its impulses by dt_
  // (x = x + delta + dt_ M^-1 J): over a virtual step the momentum impulse is J dt_ / step.
  auto drift_on_rods = [&](const std::vector<Vec3>& x, std::vector<Vec3>& momenta, double step,
                           std::vector<Vec3>& to) {
    const std::vector<double>& mass = system.particles.mass;
    std::vector<Vec3> delta(n), impulse(n);
    for (std::size_t i = 0; i < n; ++i) delta[i] = momenta[i] * (step / mass[i]);
    solve_positions(system, rods, ws_.all_equality, x, delta, impulse);
    to.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      to[i] = x[i] + delta[i] + impulse[i] * (dt_ / mass[i]);
      momenta[i] += impulse[i] * (dt_ / step);
    }
  };
  auto project_on_rods = [&](const std::vector<Vec3>& x, std::vector<Vec3>& momenta) {
    project_momenta(system, rods, x, momenta);
  };
  const RodStages stages{rods, drift_on_rods, project_on_rods};
  const RodStages* rod_stages = rods.empty() ? nullptr : &stages;
  const int steps = shadow_remainder_steps_;
  const auto before =
      shadow_remainder(engine_, system, ws_.q, ws_.p_start, moving, dt_, -dt_, steps, rod_stages);
  const auto after = shadow_remainder(engine_, system, system.particles.position, p, moving, dt_,
                                      dt_, steps, rod_stages);
  stats_ = counted;
  engine_.compute(system, true);
  if (!before || !after) return;
  restore_energy(system, touched, target, p, shadow_target + *before - *after);
}

void Gvi::step_with_impact_times(System& system, bool tally) {
  if (!constraints_.equalities.empty()) return step_with_impact_times_and_rods(system, tally);
  PhaseTimer& timer = phase_timer();
  const Phase outer = timer.enter(Phase::prediction);
  Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  step_virial_ = 0.0;
  start_step(system);  // momenta, the free prediction, a neighbour list covering it, q

  timer.enter(Phase::reflections);
  // Every pair that can meet during the drift was within the sum of its two paths at q; the
  // candidates reach four times the largest free displacement, enough unless a contact
  // speeds a particle up past twice its free path: then they are collected again.
  const std::vector<Vec3>& f = engine_.force();
  ws_.half.resize(n);
  ws_.mid.resize(n);  // here: the accelerations F(q)/m the contacts are corrected with
  for (std::size_t i = 0; i < n; ++i) {
    ws_.half[i] = ws_.p[i] + f[i] * (0.5 * h);
    ws_.mid[i] = f[i] * (1.0 / P.mass[i]);
  }
  candidates_for(system, ws_.predicted);
  const std::int64_t max_events = std::max<std::int64_t>(1000, 100 * static_cast<std::int64_t>(n));
  DriftOutcome drift;
  drift_with_covering_rows(system, true, [&] {
    ws_.p = ws_.half;
    drift = drift_.run(ws_.nearby, P, system.box, h, ws_.q, ws_.p, ws_.x, max_events,
                       system.step + 1, &ws_.mid);
    return DriftSpan{*std::max_element(drift.path.begin(), drift.path.end()), &ws_.x,
                     &drift.vertices};
  });
  step_virial_ += drift.virial;
  stats_.active += drift.events;
  stats_.reflected += drift.events;
  stats_.fallbacks += drift.plain;

  timer.enter(Phase::momentum_update);
  // With a force, a contact inside the step meets it only at the step's ends (the kicks), so
  // each contact leaves an energy error; the step's energy is given back along the normals
  // of the rows that touched (found at their contact positions, where their gap is 0).
  bool forced = false;
  for (std::size_t i = 0; i < n && !forced; ++i) forced = f[i].x != 0 || f[i].y != 0 || f[i].z != 0;
  std::vector<Constraint>& touched = ws_.landed;
  touched.clear();
  double target = 0.0;
  std::optional<double> shadow_target;
  if (forced && drift.events > 0) {
    target = start_energy(system);
    shadow_target = start_shadow_energy(system, target);
    const double tolerance = 1e-9;
    for (const Constraint& c : ws_.nearby) {
      bool met = false;
      for (const std::vector<Vec3>& at_i : drift.vertices) {
        if (c.j < 0) {
          met = std::abs(evaluate(c, at_i.data(), system.box).gap) < tolerance;
        } else {
          for (const std::vector<Vec3>& at_j : drift.vertices) {
            const double gap = norm(system.box.minimum_image(at_i[c.i] - at_j[c.j])) - c.length;
            if (std::abs(gap) < tolerance) met = true;
          }
        }
        if (met) break;
      }
      if (met) touched.push_back(c);
    }
  }
  P.position = ws_.x;
  system.step += 1;
  system.time += h;
  engine_.compute(system, tally || !touched.empty());
  const std::vector<Vec3>& f_end = engine_.force();
  for (std::size_t i = 0; i < n; ++i) ws_.p[i] += f_end[i] * (0.5 * h);
  if (!touched.empty()) restore_energy(system, touched, target, ws_.p, shadow_target);
  if (!touched.empty() && shadow_target && shadow_remainder_steps_ > 0) {
    restore_shadow_remainder(system, touched, target, *shadow_target, ws_.p);
  }
  for (std::size_t i = 0; i < n; ++i) P.velocity[i] = ws_.p[i] * (1.0 / P.mass[i]);
  ++stats_.steps;
  previous_positions_ = ws_.q;
  timer.enter(Phase::constraint_checks);
  check_constraints(system, tally);
  finish_step();
  timer.enter(outer);
}

}  // namespace deli
