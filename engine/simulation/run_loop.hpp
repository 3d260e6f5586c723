#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/phase_timer.hpp"
#include "integrators/integrator.hpp"
#include "simulation/degrees_of_freedom.hpp"
#include "simulation/observer.hpp"

namespace deli {

struct RunStatistics {
  std::int64_t steps = 0;
  std::size_t atoms = 0;
  double loop_seconds = 0;  // the step loop only: no set-up, no final output
  std::array<double, phase_count> phase_seconds{};  // the loop's time by phase (sums to it)
  std::int64_t neighbor_builds = 0;
  bool interrupted = false;  // stopped early by SIGINT/SIGTERM, after a whole step
  double atom_steps_per_second() const;
};

struct RunOptions {
  // false: the integrator was already set up (or resumed from a checkpoint) and the state
  // it starts from was sampled by the run that wrote the checkpoint.
  bool set_up = true;
  // How the temperature is counted; unset: 3N - 3 (periodic, no constraints).
  std::optional<DegreesOfFreedom> degrees_of_freedom;
  // After set-up (which makes the velocities tangent to the rods), velocities scaled to
  // this temperature with their conserved momenta removed ([velocities] temperature).
  std::optional<double> start_temperature;
};

// Runs `steps` steps, sampling thermo at the start, every `thermo_every` steps and at the
// end. Observers see every sample; a SimulationError propagates after observers finish,
// so what was written before is kept.
RunStatistics run(System& system, Integrator& integrator, std::int64_t steps,
                  std::int64_t thermo_every, const std::vector<Observer*>& observers,
                  const RunOptions& options);
// `set_up = false`: the integrator was already set up (or resumed from a checkpoint).
RunStatistics run(System& system, Integrator& integrator, std::int64_t steps,
                  std::int64_t thermo_every, const std::vector<Observer*>& observers,
                  bool set_up = true);

}  // namespace deli
