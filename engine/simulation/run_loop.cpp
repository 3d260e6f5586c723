#include "simulation/run_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <string>

#include "core/chunk_balance.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/phase_timer.hpp"
#include "core/team_profile.hpp"
#include "simulation/interrupt.hpp"
#include "system/finite_state.hpp"

namespace deli {

namespace {
// A sample with a NaN or infinite energy stops the run before any observer writes it: the
// rows and frames before it stay as they are, the files are closed by on_finish.
void check_sample_is_finite(const System& system, const ThermoSample& s,
                            const std::vector<Vec3>& forces) {
  if (std::isfinite(s.kinetic) && std::isfinite(s.potential) && std::isfinite(s.total)) return;
  std::string message = "step " + std::to_string(system.step) + ": the energy is not finite " +
                        "(kinetic " + std::to_string(s.kinetic) + ", potential " +
                        std::to_string(s.potential) + ")";
  if (const auto bad = first_non_finite_atom(system.particles, &forces)) message += "; " + *bad;
  throw SimulationError(message +
                        ": the run blew up (a timestep too large, overlapping atoms or extreme "
                        "force-field numbers); outputs up to the previous sample are kept");
}

// Every observer finishes (closes its files) even when one fails; the first failure is
// rethrown. On an error path (`after_error`) the original error is what the user sees, so
// the observers' own failures are dropped.
void finish_all(const std::vector<Observer*>& observers, const System& system, bool after_error) {
  std::exception_ptr first;
  for (Observer* o : observers) {
    try {
      o->on_finish(system);
    } catch (...) {
      if (!first) first = std::current_exception();
    }
  }
  if (first && !after_error) std::rethrow_exception(first);
}
}  // namespace

double RunStatistics::atom_steps_per_second() const {
  return loop_seconds > 0 ? static_cast<double>(atoms) * static_cast<double>(steps) / loop_seconds
                          : 0.0;
}

RunStatistics run(System& system, Integrator& integrator, std::int64_t steps,
                  std::int64_t thermo_every, const std::vector<Observer*>& observers, bool set_up) {
  RunOptions options;
  options.set_up = set_up;
  return run(system, integrator, steps, thermo_every, observers, options);
}

RunStatistics run(System& system, Integrator& integrator, std::int64_t steps,
                  std::int64_t thermo_every, const std::vector<Observer*>& observers,
                  const RunOptions& options) {
  const bool set_up = options.set_up;
  const DegreesOfFreedom dof = options.degrees_of_freedom.value_or(
      DegreesOfFreedom::periodic_unconstrained(system.particles.size()));
  if (set_up) {
    integrator.setup(system);
    if (options.start_temperature) {
      set_temperature(system.particles, dof, *options.start_temperature);
    }
  }
  for (Observer* o : observers) o->on_start(system, steps);
  const bool shadow_wanted = std::any_of(observers.begin(), observers.end(), [](const Observer* o) {
    return o->wants_shadow_energy();
  });
  auto wants_frame = [&] {
    for (Observer* o : observers) {
      if (o->wants_frame(system.step)) return true;
    }
    return false;
  };
  // `regular`: a thermo row at a multiple of thermo_every (or the start); the last step's
  // row is not, and leaves the integrator's figures to the next regular row (a restart from
  // a checkpoint taken there writes the uninterrupted run's rows).
  auto sample = [&](bool thermo, bool frame, bool regular) {
    ThermoSample s = measure_thermo(system, integrator.forces().last(), dof);
    check_sample_is_finite(system, s, integrator.forces().force());
    if (shadow_wanted) s.shadow_energy = integrator.shadow_energy(system);
    s.bath_energy = integrator.bath_energy();
    if (s.bath_energy) s.conserved = s.total - *s.bath_energy;
    const double volume = system.box.volume();
    if (frame) {
      ThermoSample f = s;
      f.pressure += integrator.take_constraint_virial(Sampler::frame) / (3.0 * volume);
      f.integrator = integrator.take_statistics(Sampler::frame);
      for (Observer* o : observers) {
        if (o->wants_frame(system.step)) o->on_frame(system, f, integrator.forces().force());
      }
    }
    if (!thermo) return;
    s.pressure += integrator.take_constraint_virial(Sampler::thermo, !regular) / (3.0 * volume);
    s.integrator = integrator.take_statistics(Sampler::thermo, !regular);
    for (Observer* o : observers) o->on_thermo(s);
  };
  RunStatistics stats;
  stats.atoms = system.particles.size();
  const std::int64_t builds_before = integrator.forces().neighbors().builds();
  PhaseTimer& timer = phase_timer();
  auto start = std::chrono::steady_clock::now();
  try {
    // A restart's first step was sampled by the run that wrote the checkpoint.
    if (set_up) sample(true, wants_frame(), true);
    start = std::chrono::steady_clock::now();
    timer.start();
    team_profile_loop_started();
    const int threads = thread_count();
    for (std::int64_t n = 1; n <= steps; ++n) {
      // Between steps: no loop runs, and no number depends on the shares.
      rebalance_chunks(threads);
      // Rows at absolute multiples of thermo_every, as frames: a restart from any step
      // writes the rows of the uninterrupted run.
      const std::int64_t next = system.step + 1;
      const bool regular = thermo_every > 0 && next % thermo_every == 0;
      const bool thermo = regular || n == steps;
      // Observers ask about the step the integrator is about to reach.
      system.step = next;
      const bool frame = wants_frame();
      system.step -= 1;
      integrator.step(system, thermo || frame);
      const TimedPhase output(Phase::output);
      for (Observer* o : observers) o->on_step(system);
      if (thermo || frame) sample(thermo, frame, regular);
      for (Observer* o : observers) o->on_step_complete(system);
      if (interrupt_requested()) {
        stats.interrupted = true;
        stats.steps = n;
        break;
      }
      stats.steps = n;
    }
  } catch (...) {
    timer.stop();
    team_profile_loop_ended();
    finish_all(observers, system, true);
    throw;
  }
  timer.stop();
  team_profile_loop_ended();
  stats.loop_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.phase_seconds = timer.seconds();
  stats.neighbor_builds = integrator.forces().neighbors().builds() - builds_before;
  finish_all(observers, system, false);
  return stats;
}

}  // namespace deli
