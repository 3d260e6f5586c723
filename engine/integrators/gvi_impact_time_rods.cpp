// GVI's step with contact = "impact_time" when the system holds rods or strings: Verlet's
// half kick; RATTLE's constrained drift over the step, split at each contact (the contact
// time a root of the row's gap along the rod-constrained drift, the momenta reflected there
// by the generalized reflection with the rods as equalities, the drift continued from the
// contact configuration for the rest of the step); Verlet's second half kick and RATTLE's
// momentum projection; the step's energy given back along the touched rows' normals when a
// force acted. Why and what it keeps: README, "Contact treatment".
#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "core/phase_timer.hpp"
#include "integrators/gvi.hpp"

namespace deli {

namespace {

// Bisection-safeguarded regula falsi (Illinois) steps at most; each is one constrained solve.
constexpr int kRootSteps = 100;

struct Candidate {
  double time;
  std::size_t row;
};

}  // namespace

void Gvi::step_with_impact_times_and_rods(System& system, bool tally) {
  PhaseTimer& timer = phase_timer();
  const Phase outer = timer.enter(Phase::prediction);
  Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  const std::vector<Constraint>& rods = constraints_.equalities;
  step_virial_ = 0.0;
  start_step(system);
  const std::vector<Vec3>& f = engine_.force();
  ws_.half.resize(n);
  for (std::size_t i = 0; i < n; ++i) ws_.half[i] = ws_.p[i] + f[i] * (0.5 * h);
  ws_.all_equality.assign(rods.size(), true);
  bool forced = false;
  for (std::size_t i = 0; i < n && !forced; ++i) forced = f[i].x != 0 || f[i].y != 0 || f[i].z != 0;

  // The force correction of the straight drift (impact_time_drift.hpp) with rods: the drift's
  // momenta p hold (h/2 - t) F too much for a contact at time t, so the reflection's impulse
  // is the one the momenta at contact, p + (t - h/2) F projected onto the rods, would get;
  // it is added to p (for one row without rods: the normal velocity after is
  // -w + (h - 2t) a_n, as there). Refused (false: reflect p itself) where the momenta at
  // contact do not approach the row or p with that impulse would not leave it.
  std::vector<Vec3> at_contact(n), reflected(n);
  auto reflect_velocity_at_contact = [&](System& sys, const std::vector<Constraint>& rows_here,
                                         const std::vector<Vec3>& x_here, double t,
                                         std::vector<Vec3>& p_here) {
    for (std::size_t i = 0; i < n; ++i) at_contact[i] = p_here[i] + f[i] * (t - 0.5 * h);
    project_momenta(sys, rods, x_here, at_contact);
    reflected = at_contact;
    const ConstraintStatistics counted = stats_;
    const double virial_before = step_virial_;
    reflect_clusters(sys, rows_here, rods.size(), x_here, reflected);
    const Constraint& c = rows_here.back();
    const ConstraintValue value = evaluate(c, x_here.data(), sys.box);
    bool changed = false;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 impulse_i = reflected[i] - at_contact[i];
      changed = changed || impulse_i.x != 0 || impulse_i.y != 0 || impulse_i.z != 0;
      reflected[i] = p_here[i] + impulse_i;
    }
    if (!changed || normal_velocity(c, value.u, reflected, P) <= 0.0) {
      stats_ = counted;
      step_virial_ = virial_before;
      ++stats_.fallbacks;
      return false;
    }
    p_here = reflected;
    return true;
  };

  // RATTLE's position stage over time tau from positions x with momenta p: the end positions
  // into `to` and the momenta there (rod impulses included, before the velocity projection)
  // into `p_to`; returns the rods' virial. solve_positions scales its impulses by the step h
  // (x = x + delta + h M^-1 J): over tau the momentum impulse is J h / tau.
  std::vector<Vec3>& delta = ws_.free;
  std::vector<Vec3>& impulse = ws_.impulse;
  delta.resize(n);
  auto drift = [&](const std::vector<Vec3>& x, const std::vector<Vec3>& p, double tau,
                   std::vector<Vec3>& to, std::vector<Vec3>* p_to) {
    for (std::size_t i = 0; i < n; ++i) delta[i] = p[i] * (tau / P.mass[i]);
    impulse.assign(n, Vec3{});
    const double virial = solve_positions(system, rods, ws_.all_equality, x, delta, impulse);
    to.resize(n);
    for (std::size_t i = 0; i < n; ++i) to[i] = x[i] + delta[i] + impulse[i] * (h / P.mass[i]);
    if (p_to) {
      p_to->resize(n);
      for (std::size_t i = 0; i < n; ++i) (*p_to)[i] = p[i] + impulse[i] * (h / tau);
    }
    return virial * (h / tau);
  };

  // The contact configurations met, per step (for the neighbour-list and energy checks).
  std::vector<std::vector<Vec3>> vertices;
  std::vector<Constraint>& touched = ws_.landed;
  std::vector<double> path(n);
  std::vector<Vec3> x(n), p(n), end(n), p_end(n), trial(n);
  std::vector<Candidate> candidates;
  std::vector<std::pair<std::size_t, double>> closed_at_contact;  // row, gap there
  std::vector<Constraint> reflecting;
  const std::int64_t max_events = std::max<std::int64_t>(1000, 100 * static_cast<std::int64_t>(n));
  double virial = 0.0;
  std::int64_t events = 0;

  // One pass over the step with the candidate rows ws_.nearby.
  auto split_drift = [&] {
    x = ws_.q;
    p = ws_.half;
    vertices.clear();
    touched.clear();
    std::fill(path.begin(), path.end(), 0.0);
    virial = 0.0;
    events = 0;
    double now = 0.0;
    std::optional<std::size_t> just_reflected;
    auto move_to = [&](const std::vector<Vec3>& to) {
      for (std::size_t i = 0; i < n; ++i) path[i] += norm(to[i] - x[i]);
      x = to;
    };
    for (;;) {
      const double rest = h - now;
      if (!(rest > 0.0)) return;  // the last contact closed the step
      const double rod_virial = drift(x, p, rest, end, &p_end);
      // Candidates: the rows whose gap closes along the chord from x to the drift's end (the
      // constrained path's secant), earliest first.
      candidates.clear();
      for (std::size_t r = 0; r < ws_.nearby.size(); ++r) {
        const Constraint& c = ws_.nearby[r];
        Vec3 d, v;
        if (c.j >= 0) {
          d = system.box.minimum_image(x[c.i] - x[c.j]);
          v = ((end[c.i] - x[c.i]) - (end[c.j] - x[c.j])) * (1.0 / rest);
        } else {
          d = x[c.i] - c.point;
          v = (end[c.i] - x[c.i]) * (1.0 / rest);
        }
        const std::optional<double> t = closing_time(c, d, v);
        if (t && *t <= rest) candidates.push_back({*t, r});
      }
      std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
        return a.time != b.time ? a.time < b.time : a.row < b.row;
      });
      auto gap_after = [&](const Constraint& c, double t) {
        drift(x, p, t, trial, nullptr);
        return gap_of(c, trial.data(), system.box);
      };
      // The time in [lo, hi] where row c's gap, open (g_lo > 0) after lo and closed
      // (g_hi <= 0) after hi along the constrained drift, reaches 0; the open side, so the
      // contact configuration does not overlap. Nothing where the row is passed over.
      // A row touching at lo (a contact met earlier in the step, whose gap at x is rounding)
      // first needs a time where it is open after its contact: halving from hi towards lo.
      // Where it never opens measurably, it closes at lo, unless its reflection at x has
      // just turned it away (a reflection there would change nothing: passed over).
      auto contact_time = [&](const Constraint& c, bool reflected_here, double lo, double g_lo,
                              double hi, double g_hi) -> std::optional<double> {
        const double touching = 1e-13 * std::max(1.0, c.length);
        const double span = hi - lo;
        for (int s = 1; s <= kRootSteps && g_lo <= touching; ++s) {
          const double t = lo + std::ldexp(span, -s);
          if (!(t - lo > 1e-15 * h)) break;
          const double g = gap_after(c, t);
          if (g > touching) {
            lo = t, g_lo = g;
          } else if (g <= 0.0) {
            hi = t, g_hi = g;
          }
        }
        if (g_lo <= touching) {
          if (reflected_here) return std::nullopt;
          return lo;
        }
        // Bisection-safeguarded regula falsi (Illinois: the end that stays is down-weighted,
        // so both ends converge).
        int kept = 0;
        for (int s = 0; s < kRootSteps && g_lo > touching && hi - lo > 1e-15 * h; ++s) {
          double t = lo + (hi - lo) * g_lo / (g_lo - g_hi);
          if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
          const double g = gap_after(c, t);
          if (g > 0.0) {
            lo = t, g_lo = g;
            if (kept == -1) g_hi *= 0.5;
            kept = -1;
          } else {
            hi = t, g_hi = g;
            if (kept == 1) g_lo *= 0.5;
            kept = 1;
          }
        }
        return lo;
      };
      // The first candidate whose gap really closes along the constrained drift: its contact
      // time bracketed between a time where the gap is open and one where it is closed. The
      // row just reflected is a candidate too: the rods bend the drift, so a row that leaves
      // at its contact can close again later in the step.
      std::optional<std::size_t> row;
      double tau = 0.0;
      for (const Candidate& k : candidates) {
        const Constraint& c = ws_.nearby[k.row];
        const bool reflected_here = just_reflected && *just_reflected == k.row;
        const double open_gap = gap_of(c, x.data(), system.box);
        if (open_gap <= 0.0) {
          if (reflected_here) continue;  // turned away at this very configuration
          row = k.row;
          tau = 0.0;
          break;
        }
        double lo = 0.0, g_lo = open_gap, hi = rest, g_hi = gap_of(c, end.data(), system.box);
        if (k.time > 0.0 && k.time < rest) {
          const double g = gap_after(c, k.time);
          if (g > 0.0) {
            lo = k.time, g_lo = g;
          } else {
            hi = k.time, g_hi = g;
          }
        }
        if (g_hi > 0.0) continue;  // the constrained drift passes by (or grazes)
        const std::optional<double> t = contact_time(c, reflected_here, lo, g_lo, hi, g_hi);
        if (!t) continue;
        row = k.row;
        tau = *t;
        break;
      }
      // The chord orders the candidates only roughly and misses rows the bent drift closes
      // on its own: a row open at x but closed at the contact configuration met its own
      // contact earlier, inside [0, tau]; it is the one taken (repeated until none is).
      for (std::size_t pass = 0; row && tau > 0.0 && pass < ws_.nearby.size(); ++pass) {
        drift(x, p, tau, trial, nullptr);
        closed_at_contact.clear();
        for (std::size_t r = 0; r < ws_.nearby.size(); ++r) {
          const double g = gap_of(ws_.nearby[r], trial.data(), system.box);
          if (r != *row && g <= 0.0 && gap_of(ws_.nearby[r], x.data(), system.box) > 0.0) {
            closed_at_contact.emplace_back(r, g);
          }
        }
        std::optional<std::size_t> earliest;
        double t_earliest = tau;
        for (const auto& [r, g_closed] : closed_at_contact) {
          const Constraint& c = ws_.nearby[r];
          const bool reflected_here = just_reflected && *just_reflected == r;
          const std::optional<double> t =
              contact_time(c, reflected_here, 0.0, gap_of(c, x.data(), system.box), tau, g_closed);
          if (t && *t < t_earliest) earliest = r, t_earliest = *t;
        }
        if (!earliest) break;
        row = earliest;
        tau = t_earliest;
      }
      if (!row) {
        virial += rod_virial;
        move_to(end);
        p = p_end;
        return;
      }
      if (tau > 0.0) {
        virial += drift(x, p, tau, end, &p_end);
        move_to(end);
        p = p_end;
        now += tau;
      }
      if (++events > max_events) {
        throw SimulationError("step " + std::to_string(system.step + 1) + ": more than " +
                              std::to_string(max_events) +
                              " contacts in one step of the impact-time drift with rods (a "
                              "row held closed by the rods bounces for ever); use [integrator] "
                              "contact = \"paper\"");
      }
      // At the contact configuration: RATTLE's momentum projection onto the rods, then the
      // reflection off the row with the rods as equalities (its normal projected onto their
      // cotangent space).
      virial += project_momenta(system, rods, x, p);
      reflecting = rods;
      reflecting.push_back(ws_.nearby[*row]);
      const double before = step_virial_;
      if (!forced || !reflect_velocity_at_contact(system, reflecting, x, now, p)) {
        reflect_clusters(system, reflecting, rods.size(), x, p);
      }
      virial += step_virial_ - before;
      step_virial_ = before;
      touched.push_back(ws_.nearby[*row]);
      vertices.push_back(x);
      just_reflected = row;
    }
  };

  timer.enter(Phase::reflections);
  drift(ws_.q, ws_.half, h, end, nullptr);
  candidates_for(system, end);
  const bool pairs_matter = engine_.neighbors().cutoff() > 0;
  drift_with_covering_rows(system, pairs_matter, [&] {
    split_drift();
    return DriftSpan{*std::max_element(path.begin(), path.end()), &x, &vertices};
  });
  step_virial_ += virial;
  stats_.active += events;

  timer.enter(Phase::momentum_update);
  const double target = forced && events > 0 ? start_energy(system) : 0.0;
  const std::optional<double> shadow_target =
      forced && events > 0 ? start_shadow_energy(system, target) : std::nullopt;
  if (!forced) touched.clear();
  ws_.x = x;
  ws_.x_largest2 = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    ws_.x_largest2 = std::max(ws_.x_largest2, norm2(x[i] - ws_.q[i]));
  ws_.x_builds = engine_.neighbors().builds();
  P.position = x;
  system.step += 1;
  system.time += h;
  engine_.compute(system, tally || !touched.empty());
  const std::vector<Vec3>& f_end = engine_.force();
  for (std::size_t i = 0; i < n; ++i) p[i] += f_end[i] * (0.5 * h);
  step_virial_ += project_momenta(system, rods, P.position, p);
  if (!touched.empty()) restore_energy(system, touched, target, p, shadow_target);
  if (!touched.empty() && shadow_target && shadow_remainder_steps_ > 0) {
    restore_shadow_remainder(system, touched, target, *shadow_target, p);
  }
  ws_.p = p;
  for (std::size_t i = 0; i < n; ++i) P.velocity[i] = p[i] * (1.0 / P.mass[i]);
  ++stats_.steps;
  previous_positions_ = ws_.q;
  timer.enter(Phase::constraint_checks);
  check_constraints(system, tally);
  finish_step();
  timer.enter(outer);
}

}  // namespace deli
