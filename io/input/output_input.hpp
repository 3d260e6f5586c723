#pragma once

#include <vector>

#include "input/output_paths.hpp"
#include "input/run_input.hpp"
#include "input/toml_table.hpp"

namespace deli {

// Reads [output]: thermo, checkpoint, dump, trajectory, final_data and log (into input);
// returns the files they name, for check_output_paths.
std::vector<OutputFile> read_output(TomlTable& root, RunInput& input);

}  // namespace deli
