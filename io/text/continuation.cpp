#include "text/continuation.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/error.hpp"

namespace deli {

bool cut_back_after_step(const std::string& path, std::int64_t step,
                         const RecordStep& record_step) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::vector<std::string> lines;
  std::vector<std::uintmax_t> offsets;
  std::uintmax_t offset = 0;
  for (std::string line; std::getline(in, line);) {
    offsets.push_back(offset);
    offset += line.size() + 1;
    lines.push_back(std::move(line));
  }
  in.close();
  std::uintmax_t keep = std::filesystem::file_size(path);
  // A line without its newline was cut short (a killed run): never append after it.
  if (!lines.empty() && offset > keep) keep = offsets.back();
  for (std::size_t k = 0; k < lines.size(); ++k) {
    std::optional<std::int64_t> at;
    try {
      at = record_step(lines, k);
    } catch (const std::logic_error&) {  // std::stoll on a damaged line
      throw InputError(path + ":" + std::to_string(k + 1) +
                       ": a record of the run being continued has no readable step; the "
                       "file is damaged: restore it or remove it to start it afresh");
    }
    if (offsets[k] < keep && at && *at > step) {
      keep = offsets[k];
      break;
    }
  }
  std::error_code error;
  std::filesystem::resize_file(path, keep, error);
  if (error) {
    throw InputError(path + ": cannot cut the file back to the checkpoint's step (" +
                     error.message() + "); check that it is writable");
  }
  return keep > 0;
}

}  // namespace deli
