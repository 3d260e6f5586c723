#pragma once

#include <array>
#include <string>

#include "system/system.hpp"

namespace deli {

struct LammpsDataOptions {
  std::array<bool, 3> periodic{true, true, true};
  // "" = take the style from the "Atoms # style" comment, or else infer it from the column count.
  std::string atom_style;
};

// A coefficient section as LAMMPS write_data writes it: "Pair Coeffs # lj/cut" then one
// line per type ("type epsilon sigma"), or "PairIJ Coeffs" per type pair ("i j epsilon
// sigma cutoff"), "Bond Coeffs # fene", "Angle Coeffs # harmonic" and "Dihedral Coeffs #
// harmonic" per type; a hybrid style's section ("Bond Coeffs # hybrid") names each row's
// style after its type ("1 fene 30 1.5 1 1"). The numbers are kept as written; the
// force-field reader gives them their meaning.
struct CoefficientRow {
  std::vector<int> types;  // 0-based: one type, or two for PairIJ
  std::string style;       // a hybrid section's row names its style ("1 fene 30 1.5 1 1")
  std::vector<double> values;
  long line = 0;
};
struct CoefficientSection {
  long line = 0;      // 0: the file has none
  std::string style;  // from the "# style" comment, "" if none
  std::vector<CoefficientRow> rows;
};

struct LammpsDataFile {
  // Particles sorted by atom id ascending; atom_types carry the Masses entries.
  System system;
  std::string atom_style;  // atomic | bond | angle | molecular | full
  bool has_velocities = false;
  std::string path;
  CoefficientSection pair, pair_ij, bond, angle, dihedral;
};

// Reads a LAMMPS data file (as LAMMPS write_data writes it) restricted to what deli models:
// orthorhombic box, atoms, masses, velocities, bonds, angles, dihedrals and their
// coefficient sections. Anything else (impropers, charges, triclinic boxes) is an InputError
// naming file:line.
LammpsDataFile read_lammps_data(const std::string& path, const LammpsDataOptions& options);

// Writes a file LAMMPS read_data accepts; doubles carry 17 significant digits so that
// read_lammps_data gives back bit-identical values.
void write_lammps_data(const System& system, const std::string& path, const std::string& atom_style,
                       const std::string& title);

}  // namespace deli
