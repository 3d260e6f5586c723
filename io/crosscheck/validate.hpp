#pragma once

#include <string>
#include <vector>

#include "crosscheck/compare.hpp"
#include "input/run_input.hpp"

namespace deli {

struct ValidateOptions {
  bool openmm = true, lammps = true;
  bool openmm_cpu = false;  // CPU platform (single precision) instead of Reference
  int trajectory_steps = 100;
};

struct ValidationReport {
  EngineEvaluation deli;
  std::vector<EngineEvaluation> others;
  std::vector<Check> checks;
  std::vector<std::string> skipped;  // engines that could not take this model, and why
  bool passed() const;
  const Check* worst() const;  // the check furthest beyond (or closest to) its tolerance
};

// Evaluates the input's starting configuration in deli, then in OpenMM and LAMMPS, and
// runs `trajectory_steps` of NVE in each from the same start. deli goes first, so that a
// model deli refuses (a FENE bond beyond its limit...) never reaches LAMMPS, whose errors
// end the process.
ValidationReport validate(const RunInput& input, const ValidateOptions& options);

}  // namespace deli
