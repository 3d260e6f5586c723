#pragma once

#include <cstdint>
#include <vector>

#include "integrators/integrator.hpp"
#include "simulation/observer.hpp"

namespace deli {

struct RunStatistics {
  std::int64_t steps = 0;
  std::size_t atoms = 0;
  double loop_seconds = 0;  // the step loop only: no set-up, no final output
  std::int64_t neighbor_builds = 0;
  double atom_steps_per_second() const;
};

// Runs `steps` steps, sampling thermo at the start, every `thermo_every` steps and at the
// end. Observers see every sample; a SimulationError propagates after observers finish,
// so what was written before is kept.
RunStatistics run(System& system, Integrator& integrator, std::int64_t steps,
                  std::int64_t thermo_every, const std::vector<Observer*>& observers);

}  // namespace deli
