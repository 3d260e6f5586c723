#pragma once

#include "input/run_input.hpp"
#include "input/toml_table.hpp"

namespace deli {

// Reads [integrator]: the type, the timestep and the options of that type (into
// input.gvi, input.direct or input.collision). Needs input's constraints and force field
// read first: they decide which types and options are allowed.
void read_integrator(TomlTable& root, RunInput& input);

}  // namespace deli
