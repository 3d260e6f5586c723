#include "core/cpu_pressure.hpp"

#include <fstream>
#include <sstream>

namespace deli {

std::optional<long long> cpu_stall_total_us(const std::string& text) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("some ", 0) != 0) continue;
    const auto at = line.find("total=");
    if (at == std::string::npos) return std::nullopt;
    try {
      return std::stoll(line.substr(at + 6));
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  return std::nullopt;
}

std::optional<long long> cpu_stall_total_us() {
  std::ifstream file("/proc/pressure/cpu");
  if (!file) return std::nullopt;
  std::ostringstream text;
  text << file.rdbuf();
  return cpu_stall_total_us(text.str());
}

bool stall_means_crowded(long long stall_us, std::int64_t window_ns) {
  return window_ns > 0 && stall_us * 1000 * 3 > window_ns;
}

}  // namespace deli
