#pragma once

#include <cstdint>
#include <fstream>
#include <string>

namespace deli {

// After a failed write (a full disk) the file may end in part of a record: closes the
// stream and cuts the file back to `whole_records` bytes, the records written whole, so
// that what is left reads cleanly. Best effort: the caller reports the failure itself.
// The file's size, 0 where it has none (a device such as /dev/stdout).
std::uintmax_t bytes_in_file(const std::string& path);

void drop_partial_record(std::ofstream& out, const std::string& path, std::uintmax_t whole_records);

}  // namespace deli
