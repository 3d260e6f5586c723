#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace deli {

// Where the thread team's time goes, kind of job by kind of job (a kind: the job function
// run_on_team() was given, one per parallel loop in the code): for each, its calls, the
// calling thread's own chunks, its waits for the workers, the slowest worker's chunks, and
// the calling thread's time since the team's previous job ended (its serial work between
// loops, during which the workers wait). Off unless the environment names a file,
// DELI_TEAM_PROFILE=path, where the table is written when the process ends; then each job
// costs two clock readings on every thread. tools/team_profile.sh runs an input so and names
// the jobs' functions.
struct JobTotals {
  const void* job = nullptr;
  std::int64_t calls = 0;
  std::int64_t own_ns = 0;             // the calling thread's chunks
  std::int64_t wait_ns = 0;            // its waits for the workers after its own chunks
  std::int64_t slowest_worker_ns = 0;  // per call, the slowest worker's chunks
  std::int64_t serial_before_ns = 0;   // since the team's previous job ended
};

bool team_profile_on();
// For tests: turns the profile on or off and clears it (the file is still the environment's).
void set_team_profile(bool on);
// The profile scoped to a run's step loop, so that its table adds up to the run's loop time:
// at the loop's start what was recorded before (the set-up's jobs: the first list build, the
// first forces) is dropped and the serial time before the loop's first job counts from there;
// after its end (the final output) nothing is recorded. Nothing while the profile is off. A
// process that runs several loops (a restart chain in one test) writes the last one's.
void team_profile_loop_started();
void team_profile_loop_ended();
// The steady clock in nanoseconds: the clock of the times below (and of the team's waits).
std::int64_t steady_ns();
// One job's times in nanoseconds of steady_ns(): started, its own chunks done, every
// worker done; the slowest worker's chunks. Called by the calling thread, one job at a time.
void team_profile_record(const void* job, std::int64_t start_ns, std::int64_t own_done_ns,
                         std::int64_t done_ns, std::int64_t slowest_worker_ns);
// The totals so far, the kinds in order of their calling thread's time (own + wait), largest
// first.
std::vector<JobTotals> team_profile_totals();
// The table: a line per kind, its function as an offset into the executable or library
// holding it (hexadecimal, for addr2line) and the totals in milliseconds.
std::string team_profile_table(const std::vector<JobTotals>& totals);

}  // namespace deli
