#include "simulation/run_loop.hpp"

#include <chrono>

namespace deli {

double RunStatistics::atom_steps_per_second() const {
  return loop_seconds > 0 ? static_cast<double>(atoms) * static_cast<double>(steps) / loop_seconds
                          : 0.0;
}

RunStatistics run(System& system, Integrator& integrator, std::int64_t steps,
                  std::int64_t thermo_every, const std::vector<Observer*>& observers) {
  integrator.setup(system);
  for (Observer* o : observers) o->on_start(system, steps);
  auto sample = [&] {
    ThermoSample s = measure_thermo(system, integrator.forces().last());
    s.pressure += integrator.take_constraint_virial() / (3.0 * system.box.volume());
    s.integrator = integrator.take_statistics();
    s.shadow_energy = integrator.shadow_energy(system);
    for (Observer* o : observers) o->on_thermo(s);
  };
  sample();

  RunStatistics stats;
  stats.atoms = system.particles.size();
  const std::int64_t builds_before = integrator.forces().neighbors().builds();
  const auto start = std::chrono::steady_clock::now();
  try {
    for (std::int64_t n = 1; n <= steps; ++n) {
      const bool sampled = (thermo_every > 0 && n % thermo_every == 0) || n == steps;
      integrator.step(system, sampled);
      for (Observer* o : observers) o->on_step(system);
      if (sampled) sample();
      stats.steps = n;
    }
  } catch (...) {
    for (Observer* o : observers) o->on_finish(system);
    throw;
  }
  stats.loop_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.neighbor_builds = integrator.forces().neighbors().builds() - builds_before;
  for (Observer* o : observers) o->on_finish(system);
  return stats;
}

}  // namespace deli
