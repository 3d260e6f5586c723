#pragma once

#include <string>
#include <utility>
#include <vector>

#include "integrators/force_engine.hpp"

namespace deli {

// Advances a system by one timestep. setup() brings forces up to date before the first
// step; after every step, forces() holds those at the new positions, with energies and
// virial when the step was asked to `tally` them.
class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual std::string name() const = 0;
  virtual double timestep() const = 0;
  virtual void setup(System& system) = 0;
  virtual void step(System& system, bool tally = true) = 0;
  virtual const ForceEngine& forces() const = 0;
  // Named figures accumulated since the last call (constraint statistics), for thermo.
  virtual std::vector<std::pair<std::string, double>> take_statistics() { return {}; }
};

}  // namespace deli
