#include "bonded/bonded_style.hpp"

namespace deli {

// The registrations, each defined in its style's own file. An explicit list, not static
// self-registration: the linker drops unreferenced objects of a static library.
const BondedStyle& harmonic_bond_style();
const BondedStyle& fene_bond_style();
const BondedStyle& harmonic_angle_style();
const BondedStyle& cosine_angle_style();
const BondedStyle& harmonic_dihedral_style();

const std::vector<const BondedStyle*>& bonded_styles(BondedKind kind) {
  static const std::vector<const BondedStyle*> bonds{&harmonic_bond_style(), &fene_bond_style()};
  static const std::vector<const BondedStyle*> angles{&harmonic_angle_style(),
                                                      &cosine_angle_style()};
  static const std::vector<const BondedStyle*> dihedrals{&harmonic_dihedral_style()};
  switch (kind) {
    case BondedKind::bond:
      return bonds;
    case BondedKind::angle:
      return angles;
    case BondedKind::dihedral:
      break;
  }
  return dihedrals;
}

const BondedStyle* find_bonded_style(BondedKind kind, const std::string& name) {
  for (const BondedStyle* style : bonded_styles(kind)) {
    if (style->name == name) return style;
  }
  return nullptr;
}

}  // namespace deli
