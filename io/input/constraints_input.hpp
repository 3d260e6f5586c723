#pragma once

#include "constraints/constraint_set.hpp"
#include "input/toml_table.hpp"
#include "system/system.hpp"

namespace deli {

// Reads [constraints]: rigid bonds and explicit rods, anchor strings, hard spheres (radii
// set on the particles) and walls. Returns an empty set when the table is absent.
// `rigid_bonds` tells the force-field reader that bonds need no bond style.
ConstraintSet read_constraints(std::optional<TomlTable> table, System& system, bool& rigid_bonds);

}  // namespace deli
