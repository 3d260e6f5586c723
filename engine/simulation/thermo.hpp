#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "forces/force_field.hpp"
#include "simulation/degrees_of_freedom.hpp"
#include "system/system.hpp"

namespace deli {

// Thermodynamic state at one step. Temperature is 2 K / dof with the run's degrees of
// freedom (see DegreesOfFreedom), pressure (2 K + W) / (3 V) with W the virial, as
// LAMMPS' default thermo.
struct ThermoSample {
  std::int64_t step = 0;
  double time = 0;
  double kinetic = 0, potential = 0, total = 0;
  double temperature = 0, pressure = 0;
  double degrees_of_freedom = 0;
  Vec3 momentum;
  std::vector<std::string> term_names;
  std::vector<double> term_energies;
  // About the origin, where it is conserved: no periodic axis.
  std::optional<Vec3> angular_momentum;
  // Verlet's second-order modified energy, where the integrator and force field have one.
  std::optional<double> shadow_energy;
  // With a thermostat: the energy the bath has put in since the start, and the total
  // energy less it, conserved up to the integrator's error.
  std::optional<double> bath_energy, conserved;
  // Integrator figures since the previous sample (constraint statistics for GVI).
  std::vector<std::pair<std::string, double>> integrator;
};

ThermoSample measure_thermo(const System& system, const ForceEvaluation& evaluation,
                            const DegreesOfFreedom& dof);

double kinetic_energy(const Particles& particles);
Vec3 total_momentum(const Particles& particles);

}  // namespace deli
