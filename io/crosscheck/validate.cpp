#include "crosscheck/validate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "crosscheck/lammps_bridge.hpp"
#include "crosscheck/openmm_bridge.hpp"
#include "integrators/gvi.hpp"
#include "integrators/quickmin.hpp"
#include "integrators/velocity_verlet.hpp"
#include "neighbor/neighbor_list.hpp"

namespace deli {

const char* skip_reason_name(SkipReason reason) {
  switch (reason) {
    case SkipReason::inequality_constraints:
      return "inequality constraints";
    case SkipReason::anchors:
      return "anchors";
    case SkipReason::lammps_rod_chains:
      return "rod chains in LAMMPS";
    case SkipReason::unsupported_model:
      return "unsupported model";
  }
  return "?";
}

bool ValidationReport::passed() const {
  for (const Check& c : checks) {
    if (!c.within()) return false;
  }
  return true;
}

const Check* ValidationReport::worst() const {
  const Check* worst = nullptr;
  for (const Check& c : checks) {
    if (!worst || c.difference / c.tolerance > worst->difference / worst->tolerance) worst = &c;
  }
  return worst;
}

namespace {

// OpenMM's constraint tolerance for the rod trajectory: relative, far below the position
// tolerance (tests/crosscheck/rattle_test.cpp measured 2.5e-11 sigma after 200 steps).
constexpr double kCcmaTolerance = 1e-14;

EngineEvaluation evaluate_deli(const RunInput& input, System& system) {
  ForceEngine engine(*input.force_field, input.skin);
  const ForceEvaluation& f = engine.compute(system);
  EngineEvaluation e;
  e.engine = "deli";
  // Terms of one name (gravity and a radial field are both "external") are summed, as
  // the other engines report them.
  for (std::size_t t = 0; t < f.names.size(); ++t) {
    const auto at = std::find(e.term_names.begin(), e.term_names.end(), f.names[t]);
    if (at == e.term_names.end()) {
      e.term_names.push_back(f.names[t]);
      e.term_energies.push_back(f.energies[t]);
    } else {
      e.term_energies[at - e.term_names.begin()] += f.energies[t];
    }
  }
  e.potential = f.potential;
  e.force = engine.force();
  e.virial = f.virial.trace();
  return e;
}

std::vector<Vec3> unwrapped(const System& system) {
  std::vector<Vec3> x;
  x.reserve(system.particles.size());
  for (std::size_t i = 0; i < system.particles.size(); ++i) {
    x.push_back(system.box.unwrapped(system.particles.position[i], system.particles.image[i]));
  }
  return x;
}

enum class TrajectoryKind { verlet, rattle, none };

struct TrajectoryPlan {
  TrajectoryKind kind = TrajectoryKind::verlet;
  SkipReason reason = SkipReason::inequality_constraints;
  std::string why;
  std::vector<Constraint> rods;
};

TrajectoryPlan plan_trajectory(const RunInput& input) {
  TrajectoryPlan plan;
  const ConstraintSet& c = input.constraints;
  std::size_t anchors = 0;
  for (const Constraint& row : c.equalities) {
    if (row.kind == ConstraintKind::rod) {
      plan.rods.push_back(row);
    } else {
      ++anchors;
    }
  }
  if (c.hard_spheres || !c.walls.empty()) {
    plan.kind = TrajectoryKind::none;
    plan.reason = SkipReason::inequality_constraints;
    std::string what = c.hard_spheres ? "hard spheres" : "";
    if (!c.walls.empty()) what += std::string(what.empty() ? "" : " and ") + "walls";
    if (anchors > 0) what += " (and anchors)";
    plan.why = "the input has " + what +
               ": inequality constraints act by impulses at contacts, which neither OpenMM nor "
               "LAMMPS integrates (their walls and granular pair styles are soft potentials)";
  } else if (anchors > 0) {
    plan.kind = TrajectoryKind::none;
    plan.reason = SkipReason::anchors;
    plan.why =
        "the input has anchors (pendulum strings to fixed points): OpenMM constrains pairs of "
        "particles only and refuses constraints to massless (fixed) ones, and LAMMPS' SHAKE "
        "has no fixed points";
  } else if (!plan.rods.empty()) {
    plan.kind = TrajectoryKind::rattle;
  }
  return plan;
}

// A pair potential cut at r_c (lj/cut) drops its force F(r_c) to zero there, and its
// energy too unless shifted. A pair that lies within rounding of r_c is counted by one
// engine and not the other: in single precision (r rounded to about 1e-6 sigma) that is a
// force difference of F(r_c) on both atoms (0.144 for the chain benchmark's lj/cut 1.12:
// atoms 24530 and 7903 at r = 1.12000030). OpenMM's virial, a difference of energies at
// scale factors exp(+-h), jumps for every pair within h r_c of its cutoff: by up to
// r_c F(r_c) (the kink) and E(r_c) / 2h (the step). The tolerances widen by exactly
// what the pairs found there can cause.
struct CutoffPairs {
  double force = 0.0;   // largest, over atoms, sum of F(r_c) of its pairs within force_band
  double virial = 0.0;  // sum of the virial bound over pairs within virial_band r_c
  int force_pairs = 0, virial_pairs = 0;
};

CutoffPairs pairs_at_cutoff(const RunInput& input, const System& s, double force_band,
                            double virial_band, bool richardson, double step) {
  CutoffPairs found;
  const auto& pair = input.force_field_spec.pair;
  if (!pair) return found;
  const double reach = pair->max_cutoff() * (1.0 + virial_band) + force_band;
  NeighborList list(reach, 0.0);
  list.build(s.particles.position, s.box);
  const auto& neighbors = list.neighbors();
  const auto& offsets = list.offsets();
  std::vector<double> per_atom(s.particles.size(), 0.0);
  for (std::size_t i = 0; i < s.particles.size(); ++i) {
    for (std::size_t k = offsets[i]; k < offsets[i + 1]; ++k) {
      const std::size_t j = static_cast<std::size_t>(neighbors[k]);
      const PairCoefficient& c = pair->coefficients.at(s.particles.type[i], s.particles.type[j]);
      const double r = norm(s.box.minimum_image(s.particles.position[j] - s.particles.position[i]));
      const double rc = c.cutoff, inner = rc * (1.0 - virial_band) - force_band;
      if (std::abs(r - rc) > std::max(force_band, virial_band * rc)) continue;
      auto force_at = [&](double x) { return pair->style->force(c.values, x); };
      const double jump = pair->shift ? 0.0 : std::abs(pair->style->energy(c.values, rc));
      const double f = std::max(force_at(inner), force_at(rc));
      if (std::abs(r - rc) <= force_band) {
        per_atom[i] += f;
        per_atom[j] += f;
        ++found.force_pairs;
      }
      if (std::abs(r - rc) <= virial_band * rc) {
        // Central difference: kink r_c F, step E / 2h; Richardson's (4 D(h) - D(2h)) / 3
        // over h and 2h: 5/3 r_c F and 3/4 E / h.
        found.virial +=
            richardson ? 5.0 / 3.0 * rc * f + 0.75 * jump / step : rc * f + 0.5 * jump / step;
        ++found.virial_pairs;
      }
    }
  }
  for (double a : per_atom) found.force = std::max(found.force, a);
  return found;
}

}  // namespace

ValidationReport validate(const RunInput& input, const ValidateOptions& options) {
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  ValidationReport report;
  System start = input.system;
  if (input.minimize.max_steps > 0) {
    say("minimising as deli run does ([minimize], at most " +
        std::to_string(input.minimize.max_steps) + " steps)");
    const MinimizeResult r = quickmin(start, *input.force_field, input.skin, input.minimize);
    report.notes.push_back("the configuration compared is the input's after [minimize] (" +
                           std::to_string(r.steps) + " quickmin steps), as deli run starts");
  }
  const std::vector<std::int64_t>& ids = start.particles.id;
  say("deli: energies, forces and virial");
  {
    System s = start;
    report.deli = evaluate_deli(input, s);
  }

  const ConstraintSet& constraints = input.constraints;
  if (!constraints.empty()) {
    report.notes.push_back(
        "constraints are not part of the force field: energies, forces and virial are those "
        "of the smooth terms only (no constraint forces or impulses)");
  }
  if (input.thermostat) {
    report.notes.push_back(
        std::string("the thermostat (") +
        (input.thermostat->kind == ThermostatKind::langevin ? "langevin" : "csvr") +
        ") is not part of the comparison: a trajectory compared is NVE from the same start");
  }

  // The trajectory's start: the integrator's setup (onto the rods, velocities tangent),
  // then [velocities] temperature, as deli run does.
  const int steps = options.trajectory_steps;
  TrajectoryPlan plan = plan_trajectory(input);
  if (steps > 0 && plan.kind == TrajectoryKind::none) {
    report.skipped.push_back({"all", "trajectory", plan.reason, plan.why});
  }
  System traj_start = start;
  std::vector<Vec3> deli_positions;
  const bool run_trajectory = steps > 0 && plan.kind != TrajectoryKind::none;
  if (plan.kind == TrajectoryKind::rattle) {
    if (input.integrator != "gvi" || input.gvi.lagrangian != Lagrangian::verlet ||
        !input.gvi.reflections) {
      report.notes.push_back(
          "the rod trajectory is GVI with the Verlet Lagrangian (RATTLE), "
          "not the input's integrator");
    }
    GviOptions gvi_options = input.gvi;
    gvi_options.lagrangian = Lagrangian::verlet;
    gvi_options.reflections = true;
    gvi_options.timestep = input.timestep;
    gvi_options.skin = input.skin;
    Gvi gvi(*input.force_field, constraints, gvi_options, traj_start.particles);
    gvi.setup(traj_start);
    if (input.start_temperature) {
      set_temperature(traj_start.particles, input.degrees_of_freedom, *input.start_temperature);
    }
    if (run_trajectory) {
      say("deli: " + std::to_string(steps) + " steps of GVI (RATTLE)");
      System s = traj_start;
      Gvi stepper(*input.force_field, constraints, gvi_options, s.particles);
      stepper.setup(s);
      for (int n = 0; n < steps; ++n) stepper.step(s, false);
      deli_positions = unwrapped(s);
    }
  } else if (plan.kind == TrajectoryKind::verlet) {
    if (input.integrator != "verlet" || !constraints.empty()) {
      report.notes.push_back("the trajectory is velocity Verlet, not the input's integrator (" +
                             input.integrator + ")");
    }
    if (input.start_temperature) {
      set_temperature(traj_start.particles, input.degrees_of_freedom, *input.start_temperature);
    }
    if (run_trajectory) {
      say("deli: " + std::to_string(steps) + " steps of velocity Verlet");
      System s = traj_start;
      VelocityVerlet verlet(*input.force_field, input.skin, input.timestep);
      verlet.setup(s);
      for (int n = 0; n < steps; ++n) verlet.step(s, false);
      deli_positions = unwrapped(s);
    }
  }
  const double growth = run_trajectory ? position_tolerance_growth(steps, input.timestep) : 1.0;
  if (growth > 1.0) {
    // The tolerance passes 1e-6 sigma (where an integration difference, such as a wrong
    // half step, shows after 100 steps) after sharp_steps.
    const int sharp_steps = static_cast<int>(position_tolerance_growth(0, input.timestep) *
                                             (0.5 + std::log(1e4) / 5.0) / input.timestep);
    char line[400];
    std::snprintf(line, sizeof line,
                  "after %d steps (%.3g tau) the position tolerance is grown by exp(5 (t - 0.5)) "
                  "= %.3g: rounding differences grow so in a chaotic system%s%d steps",
                  steps, steps * input.timestep, growth,
                  growth > 1e4 ? "; beyond 1e-6 sigma positions catch only gross errors: a "
                                 "sharp test takes at most "
                               : "; a sharp test (tolerance at most 1e-6 sigma) takes at most ",
                  sharp_steps);
    report.notes.push_back(line);
  }

  if (options.openmm) {
    try {
      const std::string platform = options.openmm_cpu ? "CPU" : "Reference";
      OpenMMBridge openmm(
          start, input.force_field_spec,
          options.openmm_cpu ? OpenMMBridge::Platform::cpu : OpenMMBridge::Platform::reference,
          plan.kind == TrajectoryKind::rattle ? plan.rods : std::vector<Constraint>{},
          kCcmaTolerance);
      Tolerances tol =
          options.openmm_cpu ? single_precision_tolerances() : double_precision_tolerances(true);
      {
        // Rounding of r: in single precision a few units of 2^-24 of the largest
        // coordinate; the virial's scale steps: exp(+-1e-6) (Reference), exp(+-2e-3) (CPU).
        double largest = 0.0;
        for (const Vec3& x : start.particles.position) {
          largest = std::max({largest, std::abs(x.x), std::abs(x.y), std::abs(x.z)});
        }
        const double force_band =
            options.openmm_cpu ? 4.0 * std::ldexp(1.0, -24) * (largest + 10.0) : 0.0;
        const CutoffPairs at_cutoff =
            pairs_at_cutoff(input, start, force_band, options.openmm_cpu ? 2e-3 : 1e-6,
                            options.openmm_cpu, options.openmm_cpu ? 1e-3 : 1e-6);
        tol.force_absolute += at_cutoff.force;
        tol.virial_relative += at_cutoff.virial / std::max(std::abs(*report.deli.virial), 1.0);
        if (at_cutoff.force_pairs + at_cutoff.virial_pairs > 0) {
          char line[400];
          std::snprintf(line, sizeof line,
                        "OpenMM %s: %d pairs lie within rounding of their cutoff and %d within "
                        "the virial's scale step of it, where the force (or energy) jumps: the "
                        "force tolerance widens by %.3g, the virial's by %.3g (relative)",
                        platform.c_str(), at_cutoff.force_pairs, at_cutoff.virial_pairs,
                        at_cutoff.force,
                        at_cutoff.virial / std::max(std::abs(*report.deli.virial), 1.0));
          report.notes.push_back(line);
        }
      }
      say("OpenMM " + platform + ": energies, forces and virial");
      // Positions as stored, on which deli's external fields act.
      report.others.push_back(openmm.evaluate(start.particles.position));
      const auto checks = compare_evaluations(report.deli, report.others.back(), tol, ids);
      report.checks.insert(report.checks.end(), checks.begin(), checks.end());
      if (run_trajectory) {
        say("OpenMM " + platform + ": " + std::to_string(steps) + " steps of Verlet" +
            (plan.kind == TrajectoryKind::rattle ? " with the rods as constraints (CCMA)" : ""));
        // Unwrapped: OpenMM 7.7's CPU neighbour list crashed (chains_4000_rigid, rods as
        // constraints) when started from the positions as stored.
        const std::vector<Vec3> x = openmm.run_nve(
            unwrapped(traj_start), traj_start.particles.velocity, steps, input.timestep);
        tol.position_absolute *= growth;
        report.checks.push_back(
            compare_positions(openmm.name(), deli_positions, x, tol, ids, steps));
      }
    } catch (const UnsupportedModel& e) {
      report.skipped.push_back({"OpenMM", "everything", SkipReason::unsupported_model, e.what()});
    }
  }
  if (options.lammps) {
    // LAMMPS starts from the trajectory's state (the same positions as `start` without
    // rods; with rods it only evaluates).
    const bool lammps_trajectory = run_trajectory && plan.kind == TrajectoryKind::verlet;
    try {
      LammpsBridge lammps(lammps_trajectory ? traj_start : start, input.force_field_spec,
                          input.skin);
      Tolerances tol = double_precision_tolerances(false);
      say("LAMMPS: energies, forces and virial");
      report.others.push_back(lammps.evaluate());
      const auto checks = compare_evaluations(report.deli, report.others.back(), tol, ids);
      report.checks.insert(report.checks.end(), checks.begin(), checks.end());
      if (lammps_trajectory) {
        say("LAMMPS: " + std::to_string(steps) + " steps of fix nve");
        const auto x = lammps.run_nve(steps, input.timestep);
        tol.position_absolute *= growth;
        report.checks.push_back(
            compare_positions(lammps.name(), deli_positions, x, tol, ids, steps));
      } else if (run_trajectory && plan.kind == TrajectoryKind::rattle) {
        report.skipped.push_back(
            {"LAMMPS", "trajectory", SkipReason::lammps_rod_chains,
             "LAMMPS' fix shake and fix rattle hold clusters of at most 4 atoms bonded to one "
             "central atom; chains of rods are not such clusters"});
      }
    } catch (const UnsupportedModel& e) {
      report.skipped.push_back({"LAMMPS", "everything", SkipReason::unsupported_model, e.what()});
    }
  }
  return report;
}

}  // namespace deli
