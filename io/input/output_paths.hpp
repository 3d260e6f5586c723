#pragma once

#include <string>
#include <vector>

#include "input/toml_table.hpp"

namespace deli {

// One output file an input names, with the table that names it (for file:line messages).
struct OutputFile {
  std::string role;  // "thermo", "trajectory", "dump", "checkpoint", "final data", "log"
  std::string path;
  TomlTable table;           // holds `key`
  std::string key = "file";  // the key naming the path, for messages
};

// The path with symlinks, "." and ".." resolved, so that two names of one file compare equal.
std::string resolved_path(const std::string& path);

// Outputs never destroy inputs: refuses (InputError at the output's key) an output that is
// one of `inputs` (the input file, its data file), two outputs naming one file, and a
// checkpoint path that exists but is not a regular file holding HDF5 (a symlink, a device, a
// directory, someone's text), since a checkpoint replaces its file by a rename.
void check_output_paths(const std::vector<OutputFile>& outputs,
                        const std::vector<std::pair<std::string, std::string>>& inputs);

}  // namespace deli
