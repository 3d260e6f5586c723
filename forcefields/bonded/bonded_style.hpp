#pragma once

#include <memory>
#include <string>
#include <vector>

#include "forces/force_term.hpp"
#include "style_coefficient.hpp"

namespace deli {

enum class BondedKind { bond, angle, dihedral };

// A bond, angle or dihedral style, described once, in the style's own file: how its coefficients
// are read, the term deli computes, and how OpenMM and LAMMPS express the same potential.
// The cross-check layer needs only these strings, so the forcefields layer stays free of
// OpenMM and LAMMPS headers.
struct BondedStyle {
  BondedKind kind;
  std::string name;  // the input's style, which is LAMMPS' too
  std::vector<StyleCoefficient> coefficients;
  std::string data_form;  // what a data-file row holds, for errors: "harmonic bond ... K r0"
  // The term for the bonds (angles, dihedrals) of the system, from the coefficients by type (each
  // in `coefficients`' order, angles in radians): of every type, or of those set in `own_types` (a
  // system of several styles; the other types' rows are zeros).
  std::unique_ptr<ForceTerm> (*make_term)(const std::vector<std::vector<double>>& by_type,
                                          std::vector<char> own_types);
  // The energy as an OpenMM CustomBondForce (of r), CustomAngleForce (of theta) or
  // CustomTorsionForce (of theta) expression in the coefficients' names; empty: not
  // available in OpenMM.
  std::string openmm_energy;
  // LAMMPS' bond_style/angle_style/dihedral_style, whose coeff lines take the coefficients in order
  // (angles in degrees); empty: not available in LAMMPS.
  std::string lammps_style;
};

// The registered styles of a kind, in the order the input's errors list them.
const std::vector<const BondedStyle*>& bonded_styles(BondedKind kind);
// nullptr when no style of that kind has that name.
const BondedStyle* find_bonded_style(BondedKind kind, const std::string& name);

}  // namespace deli
