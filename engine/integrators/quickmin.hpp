#pragma once

#include <cstdint>

#include "integrators/force_engine.hpp"

namespace deli {

struct MinimizeSettings {
  std::int64_t max_steps = 0;  // 0: no minimisation
  double timestep = 0.002;
  double max_displacement = 0.05;  // per step, in sigma
  double force_tolerance = 1e-3;   // stop when the largest force component is below this
};

struct MinimizeResult {
  std::int64_t steps = 0;
  double initial_energy = 0, final_energy = 0, max_force = 0;
  bool converged = false;
};

// Damped dynamics (LAMMPS' min_style quickmin): velocities keep only their component
// along the force, and vanish when they point against it, so the energy goes downhill.
// Used to relax overlaps of a built configuration before a run. Velocities are left as
// they were, as LAMMPS' minimize does.
MinimizeResult quickmin(System& system, const ForceField& force_field, double skin,
                        const MinimizeSettings& settings);

}  // namespace deli
