#pragma once

#include <string>
#include <vector>

#include "crosscheck/evaluation.hpp"
#include "force_field_spec.hpp"
#include "system/system.hpp"

namespace deli {

// The same model in LAMMPS (`units lj`), through its C library in this process: the
// system goes through a LAMMPS data file written by deli, the force field as LAMMPS
// commands (lj/cut with every type pair given explicitly, pair_modify shift,
// special_bonds lj, the registered bond, angle and dihedral styles; bonds held as rods
// as bond_style zero; gravity as fix gravity, radial fields as fix addforce with atom-style
// variables). Open axes are
// shrink-wrapped, never inside the bounds deli gives them (boundary m). Debian's LAMMPS is built
// without exceptions: any LAMMPS error ends the process, so only models deli has already evaluated
// without error may be handed over (the validate command evaluates deli first).
class LammpsBridge {
 public:
  LammpsBridge(const System& system, const ForceFieldSpec& spec, double skin);
  ~LammpsBridge();
  LammpsBridge(const LammpsBridge&) = delete;
  LammpsBridge& operator=(const LammpsBridge&) = delete;

  std::string name() const { return "LAMMPS"; }
  // At the positions the bridge was built with.
  EngineEvaluation evaluate();
  // Unwrapped positions after `steps` of fix nve from the data file's state.
  std::vector<Vec3> run_nve(int steps, double dt);
  // Potential and kinetic energy series of fix nve + fix langevin (T, damp = damping,
  // seed; zero no) from the data file's state, or from where the previous run ended.
  // LAMMPS adds the drag -m v / damp and a uniform random force of the same variance to
  // the forces, which velocity Verlet integrates; its kinetic energy is that of the
  // full-step velocities.
  EnergySeries run_langevin(const LangevinRun& run);

 private:
  void command(const std::string& line);
  std::vector<Vec3> per_atom(const char* compute_or_name, bool is_compute);
  void bonded_style(const std::string& kind, const BondedSpec& bonded);

  void* lammps_ = nullptr;
  std::string data_path_;
  std::vector<std::int64_t> ids_;  // deli index -> atom id
  // terms of the force field
  bool has_pair_ = false, has_bonds_ = false, has_angles_ = false, has_dihedrals_ = false;
  std::vector<std::string> external_fixes_;  // fix ids whose scalar is external energy
};

}  // namespace deli
