#pragma once

#include <functional>
#include <string>
#include <vector>

#include "crosscheck/compare.hpp"
#include "input/run_input.hpp"

namespace deli {

struct ValidateOptions {
  bool openmm = true, lammps = true;
  bool openmm_cpu = false;  // CPU platform (single precision) instead of Reference
  int trajectory_steps = 100;
  // Called with one line at the start of each phase (minimisation, each engine's
  // evaluation and trajectory): long validations say where they are.
  std::function<void(const std::string&)> progress;
};

// Why a check was not made. Each reason is documented in README (deli validate).
enum class SkipReason {
  inequality_constraints,  // hard spheres or walls: impulses at contacts, in no other engine
  anchors,                 // pendulum strings to fixed points: no OpenMM/LAMMPS constraint
  lammps_rod_chains,       // LAMMPS' SHAKE/RATTLE holds small clusters only, not rod chains
  unsupported_model,       // the engine cannot express the model (the message says what)
};
const char* skip_reason_name(SkipReason reason);

struct SkippedCheck {
  std::string engine;  // "OpenMM", "LAMMPS" or "all"
  std::string check;   // "trajectory", "everything"
  SkipReason reason;
  std::string why;
};

struct ValidationReport {
  EngineEvaluation deli;
  std::vector<EngineEvaluation> others;
  std::vector<Check> checks;
  std::vector<SkippedCheck> skipped;
  // What the comparison is of, and what it leaves out (constraints, thermostat, the
  // input's own integrator), one sentence each.
  std::vector<std::string> notes;
  bool passed() const;
  const Check* worst() const;  // the check furthest beyond (or closest to) its tolerance
};

// Evaluates the input's starting configuration (minimised first when the input asks, as
// `deli run` does) in deli, then in OpenMM and LAMMPS: every force-field term, the total,
// every force component and the virial. Constraints are not part of the force field: with
// rods only, a `trajectory_steps` trajectory of GVI (RATTLE) is compared with OpenMM's
// constrained Verlet (CCMA); without constraints, velocity Verlet with OpenMM's Verlet and
// LAMMPS' fix nve (NVE, whatever thermostat the input has). With hard spheres, walls or
// anchors the trajectory is skipped, with the reason. deli goes first, so that a model
// deli refuses (a FENE bond beyond its limit...) never reaches LAMMPS, whose errors end
// the process.
ValidationReport validate(const RunInput& input, const ValidateOptions& options);

}  // namespace deli
