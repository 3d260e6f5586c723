#pragma once

#include <string>
#include <vector>

#include "force_field_spec.hpp"
#include "input/system_input.hpp"
#include "input/toml_table.hpp"
#include "system/system.hpp"

namespace deli {

// Reads [forcefield]: special_bonds, pair, bond, angle, dihedral and external. Coefficients come
// from the data file's sections first, then the input's coeffs, which win; `notes` says which came
// from where. `rigid_bonds`: the bonds are rods and take no bond style.
ForceFieldSpec read_force_field(TomlTable& root, const System& system, bool rigid_bonds,
                                const DataCoefficients& data, std::vector<std::string>& notes);

}  // namespace deli
