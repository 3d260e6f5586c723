#pragma once

#include <cstdlib>
#include <string>

namespace deli::testing {

// The sanitizer pass (tools/sanitize.sh) sets DELI_SANITIZER_SHORT_RUNS=1, where the
// sanitizers make every step 8 to 15 times slower. The long statistical tests and the
// whole-system cross-checks then run a short prefix of their steps through the same code and
// assert only what a short run can: values finite, no overlap, bounds that hold over every
// prefix of the full run (a maximum over fewer steps is no larger). Their statistical
// assertions (means and variances against the ensemble, trends, ratios) are left to the plain
// pass (./setup.sh test), which runs every test in full.
inline bool short_runs() {
  const char* value = std::getenv("DELI_SANITIZER_SHORT_RUNS");
  return value != nullptr && std::string(value) != "" && std::string(value) != "0";
}

// `full` in the plain pass, `prefix` under the sanitizers.
template <typename Count>
Count steps_or_prefix(Count full, Count prefix) {
  return short_runs() ? prefix : full;
}

}  // namespace deli::testing
