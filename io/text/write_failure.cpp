#include "text/write_failure.hpp"

#include <filesystem>
#include <system_error>

namespace deli {

std::uintmax_t bytes_in_file(const std::string& path) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  return error ? 0 : size;
}

void drop_partial_record(std::ofstream& out, const std::string& path,
                         std::uintmax_t whole_records) {
  out.close();
  std::error_code error;
  if (std::filesystem::is_regular_file(path, error) && bytes_in_file(path) > whole_records) {
    std::filesystem::resize_file(path, whole_records, error);
  }
}

}  // namespace deli
