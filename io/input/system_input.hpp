#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "input/lammps_data.hpp"
#include "input/toml_table.hpp"
#include "system/system.hpp"

namespace deli {

// The force-field coefficients a data file carries (LAMMPS write_data writes them).
struct DataCoefficients {
  std::string file;
  CoefficientSection pair, pair_ij, bond, angle, dihedral;
};

// Reads [system]: one of a LAMMPS data file (its coefficient sections go to
// `coefficients`), [system.lattice] or [system.chains], and the boundary.
System read_system(TomlTable& t, const std::filesystem::path& input_dir,
                   DataCoefficients& coefficients);

// Reads [velocities]: Maxwell-Boltzmann velocities at its temperature, which it returns
// (nothing without the table).
std::optional<double> read_velocities(TomlTable& root, System& system);

// Numbers that are each finite can still combine into an infinite box (a tiny density, a
// huge lattice) or atoms the builders placed at infinity; nothing downstream checks that.
void check_system_is_finite(const System& system, const TomlTable& root);

}  // namespace deli
