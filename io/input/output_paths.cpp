#include "input/output_paths.hpp"

#include <filesystem>
#include <fstream>

namespace deli {

namespace fs = std::filesystem;

std::string resolved_path(const std::string& path) {
  std::error_code error;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(path), error);
  return error ? fs::absolute(path).lexically_normal().string() : resolved.string();
}

namespace {
bool starts_as_hdf5(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char signature[8] = {};
  in.read(signature, sizeof signature);
  return in && std::string(signature, 8) == std::string("\x89HDF\r\n\x1a\n", 8);
}

void check_checkpoint_target(const OutputFile& out, const std::string& path) {
  std::error_code error;
  const fs::file_status status = fs::symlink_status(path, error);
  if (error || status.type() == fs::file_type::not_found) return;
  if (status.type() != fs::file_type::regular) {
    out.table.fail(path +
                       " exists and is not a regular file (a symlink, a device or a directory); "
                       "a checkpoint replaces its file: name another file",
                   "file");
  }
  if (fs::file_size(path, error) > 0 && !starts_as_hdf5(path)) {
    out.table.fail(path +
                       " exists and is not a checkpoint (not HDF5); a checkpoint replaces its "
                       "file: move it aside or name another file",
                   "file");
  }
}
}  // namespace

void check_output_paths(const std::vector<OutputFile>& outputs,
                        const std::vector<std::pair<std::string, std::string>>& inputs) {
  std::vector<std::pair<std::string, std::string>> taken;  // resolved path, role
  for (const auto& [role, path] : inputs) taken.emplace_back(resolved_path(path), role);
  const std::size_t input_count = taken.size();
  for (const OutputFile& out : outputs) {
    if (out.path.empty()) continue;
    std::vector<std::string> names{out.path};
    if (out.role == "checkpoint") names.push_back(out.path + ".partial");  // written aside
    for (const std::string& name : names) {
      const std::string resolved = resolved_path(name);
      for (std::size_t k = 0; k < taken.size(); ++k) {
        if (taken[k].first != resolved) continue;
        if (k < input_count) {
          out.table.fail(name + " is the run's " + taken[k].second + "; writing the " + out.role +
                             " there would destroy it: name another file",
                         "file");
        }
        out.table.fail(
            name + " is also the " + taken[k].second + " output; give each output its own file",
            "file");
      }
    }
    for (const std::string& name : names) taken.emplace_back(resolved_path(name), out.role);
    if (out.role == "checkpoint") check_checkpoint_target(out, out.path);
  }
}

}  // namespace deli
