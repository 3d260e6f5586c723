#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bonded/bonded_style.hpp"
#include "forces/force_field.hpp"
#include "pair/pair_style.hpp"

namespace deli {

struct System;

// The force field as the user specified it, fully resolved (mixing applied, every type
// covered): what deli builds its force terms from, and what the OpenMM and LAMMPS
// bridges translate, so that all three engines see the same model.
struct PairSpec {
  const PairStyle* style = nullptr;
  bool shift = false;
  PairCoefficients coefficients{1, 0.0};  // per type pair, cutoffs included
  double max_cutoff() const;
};

// The bonds', angles' or dihedrals' style and its coefficients by type, each in the
// style's coefficient order (angles in radians).
struct BondedSpec {
  const BondedStyle* style = nullptr;             // the table's
  std::vector<const BondedStyle*> style_by_type;  // the table's, or the type's own
  std::vector<std::vector<double>> by_type;
  // The styles in use, each once, in the order of their first type.
  std::vector<const BondedStyle*> styles() const;
};

struct ForceFieldSpec {
  std::array<double, 3> special_lj{0.0, 0.0, 0.0};  // LAMMPS special_bonds lj 1-2 1-3 1-4
  std::optional<PairSpec> pair;
  std::optional<BondedSpec> bond;
  std::optional<BondedSpec> angle;
  std::optional<BondedSpec> dihedral;
  std::optional<Vec3> gravity;  // uniform field, force per unit mass
  struct Radial {
    bool inverse_square = false;  // else polynomial in |x - c|^2
    Vec3 center;
    std::vector<double> coefficients;  // [A] or [a0, a1, ...]
  };
  std::vector<Radial> radial;
};

std::unique_ptr<ForceField> build_force_field(const ForceFieldSpec& spec, const System& system);

}  // namespace deli
