#include "simulation/timing_table.hpp"

#include <cstdio>

namespace deli {

std::string timing_table(const RunStatistics& stats) {
  std::string out = "phase                    seconds  % of loop\n";
  char line[96];
  const double total = stats.loop_seconds > 0 ? stats.loop_seconds : 1.0;
  for (std::size_t k = 0; k < phase_count; ++k) {
    const double s = stats.phase_seconds[k];
    if (s <= 0.0) continue;
    std::snprintf(line, sizeof line, "%-22s %9.3f %10.1f\n", phase_name(static_cast<Phase>(k)), s,
                  100.0 * s / total);
    out += line;
  }
  return out;
}

}  // namespace deli
