#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace deli {

// One engine's energies, forces and virial for the same configuration, forces indexed
// like deli's particles. Energy terms are named as deli names them (pair, bond, angle, dihedral).
struct EngineEvaluation {
  std::string engine;
  std::vector<std::string> term_names;
  std::vector<double> term_energies;
  double potential = 0.0;
  std::vector<Vec3> force;
  std::optional<double> virial;  // trace of sum r_ij (x) f_ij
};

// A Langevin run at constant temperature, the same for every engine: temperature T
// (reduced, k_B = 1), damping = 1 / friction (time units), timestep, `samples` samples taken
// every `every` steps after `equilibration` steps, and the engine's random seed (> 0).
struct LangevinRun {
  double temperature = 1.0;
  double damping = 1.0;
  double timestep = 0.005;
  int equilibration = 0;
  int samples = 0;
  int every = 1;
  int seed = 1;
};

// Total potential and kinetic energy at each sample of a run.
struct EnergySeries {
  std::vector<double> potential, kinetic;
};

// A model the other engine cannot express (e.g. OpenMM with mixed periodicity).
class UnsupportedModel : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace deli
