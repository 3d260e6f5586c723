#pragma once

#include <cmath>
#include <string>

namespace deli {

// One coefficient of a style, in LAMMPS' coefficient order: its name in the input's coeffs
// (and as an OpenMM parameter), the check the input's value must pass, and its unit.
struct StyleCoefficient {
  enum class Check { any, positive, non_negative, sign, non_negative_integer };
  std::string name;
  Check check = Check::any;
  bool degrees = false;  // given (input, data file, LAMMPS) in degrees, held in radians
};

// What a value failing `check` must be instead ("must be positive"); "" when it passes.
inline std::string coefficient_violation(StyleCoefficient::Check check, double value) {
  switch (check) {
    case StyleCoefficient::Check::positive:
      return value > 0 ? "" : "must be positive";
    case StyleCoefficient::Check::non_negative:
      return value >= 0 ? "" : "must not be negative";
    case StyleCoefficient::Check::sign:
      return value == 1 || value == -1 ? "" : "must be +1 or -1";
    case StyleCoefficient::Check::non_negative_integer:
      return value >= 0 && value == std::floor(value) && value < 1e9
                 ? ""
                 : "must be a whole number, 0 or more";
    case StyleCoefficient::Check::any:
      break;
  }
  return "";
}

}  // namespace deli
