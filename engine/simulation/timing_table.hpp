#pragma once

#include <string>

#include "simulation/run_loop.hpp"

namespace deli {

// The loop's time by phase, one line each (seconds and percent of the loop), as LAMMPS
// prints after a run. Phases that took no time are left out.
std::string timing_table(const RunStatistics& stats);

}  // namespace deli
