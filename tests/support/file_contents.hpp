#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace deli::testing {

// The whole file at `path`, byte for byte; empty when it cannot be read (the comparison that
// follows then fails and names the file).
inline std::string file_contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace deli::testing
