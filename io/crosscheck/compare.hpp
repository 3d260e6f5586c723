#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "crosscheck/evaluation.hpp"

namespace deli {

// How closely another engine must agree with deli. Relative differences are taken
// against the larger magnitude of the two values, or 1 (epsilon) if both are smaller.
struct Tolerances {
  double energy_relative;  // each term and the total
  double force_absolute;   // every force component, epsilon/sigma
  double virial_relative;
  double position_absolute;  // after the trajectory, sigma
};

// OpenMM's Reference platform and LAMMPS compute in double precision: they agree with each
// other to about 1e-14 in energy and 1e-12 in forces, and deli must do as well. The virial
// is a sum of terms about ten times its size and of both signs, and LAMMPS hands it over
// as a pressure (divided, then multiplied back by 3V): 1e-10. OpenMM has no virial: it is
// a central difference of the energy under scaling (error about 1e-7 in double). After 100
// steps positions were measured to agree to 1.8e-12 sigma (OpenMM) and 4e-14 (LAMMPS) on
// every shipped input: 1e-10 leaves a factor 50 for chaos to amplify rounding, and catches
// any integration difference (units, masses, the leapfrog half step), which shows at 1e-6
// or more; longer runs grow it (position_tolerance_growth). The CPU platform computes
// forces in single precision: energy 1e-5, forces 1e-3, virial 1e-3, positions 1e-3, set
// over every shipped input (worst 1.2e-7, 4.7e-4, 1.8e-4, 2.1e-5; README). Pairs within
// rounding of their cutoff widen the force and virial tolerances (validate.cpp).
Tolerances double_precision_tolerances(bool numeric_virial);
Tolerances single_precision_tolerances();

struct Check {
  std::string engine, quantity;
  double deli_value = 0, other_value = 0;  // for energies and the virial
  double difference = 0;                   // relative or absolute, as `tolerance`
  double tolerance = 0;
  std::string where;  // atom id, for forces and positions
  bool within() const { return difference <= tolerance; }
};

double relative_difference(double a, double b);

// The factor by which the position tolerance (set for 100 steps) grows after `steps`
// steps of `timestep`: rounding differences grow exponentially in a chaotic system.
double position_tolerance_growth(int steps, double timestep);

// Term by term (matched by name), total, largest force component difference, virial.
std::vector<Check> compare_evaluations(const EngineEvaluation& deli, const EngineEvaluation& other,
                                       const Tolerances& tolerances,
                                       const std::vector<std::int64_t>& ids);
Check compare_positions(const std::string& engine, const std::vector<Vec3>& deli,
                        const std::vector<Vec3>& other, const Tolerances& tolerances,
                        const std::vector<std::int64_t>& ids, int steps);

}  // namespace deli
