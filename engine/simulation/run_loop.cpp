#include "simulation/run_loop.hpp"

#include <chrono>

#include "core/phase_timer.hpp"
#include "simulation/interrupt.hpp"

namespace deli {

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
  auto wants_frame = [&] {
    for (Observer* o : observers) {
      if (o->wants_frame(system.step)) return true;
    }
    return false;
  };
  auto sample = [&](bool thermo, bool frame) {
    ThermoSample s = measure_thermo(system, integrator.forces().last(), dof);
    s.shadow_energy = integrator.shadow_energy(system);
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
    s.pressure += integrator.take_constraint_virial(Sampler::thermo) / (3.0 * volume);
    s.integrator = integrator.take_statistics(Sampler::thermo);
    for (Observer* o : observers) o->on_thermo(s);
  };
  // A restart's first step was sampled by the run that wrote the checkpoint.
  if (set_up) sample(true, wants_frame());

  RunStatistics stats;
  stats.atoms = system.particles.size();
  const std::int64_t builds_before = integrator.forces().neighbors().builds();
  PhaseTimer& timer = phase_timer();
  const auto start = std::chrono::steady_clock::now();
  timer.start();
  try {
    for (std::int64_t n = 1; n <= steps; ++n) {
      const bool thermo = (thermo_every > 0 && n % thermo_every == 0) || n == steps;
      // Observers ask about the step the integrator is about to reach.
      system.step += 1;
      const bool frame = wants_frame();
      system.step -= 1;
      integrator.step(system, thermo || frame);
      const TimedPhase output(Phase::output);
      for (Observer* o : observers) o->on_step(system);
      if (thermo || frame) sample(thermo, frame);
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
    for (Observer* o : observers) o->on_finish(system);
    throw;
  }
  timer.stop();
  stats.loop_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.phase_seconds = timer.seconds();
  stats.neighbor_builds = integrator.forces().neighbors().builds() - builds_before;
  for (Observer* o : observers) o->on_finish(system);
  return stats;
}

}  // namespace deli
