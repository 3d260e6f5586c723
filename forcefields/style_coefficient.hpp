#pragma once

#include <string>

namespace deli {

// One coefficient of a style, in LAMMPS' coefficient order: its name in the input's coeffs
// (and as an OpenMM parameter), the check the input's value must pass, and its unit.
struct StyleCoefficient {
  enum class Check { any, positive, non_negative };
  std::string name;
  Check check = Check::any;
  bool degrees = false;  // given (input, data file, LAMMPS) in degrees, held in radians
};

}  // namespace deli
