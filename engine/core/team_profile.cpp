#include "core/team_profile.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <unordered_map>

namespace deli {

namespace {

struct Profile {
  bool on = false;
  const char* file = nullptr;
  std::unordered_map<const void*, JobTotals> totals;
  std::int64_t last_done_ns = -1;  // the previous job's end; -1 before the first
  bool recording = true;           // false after a step loop's end

  Profile() {
    file = std::getenv("DELI_TEAM_PROFILE");
    on = file != nullptr && *file != '\0';
  }
  ~Profile() {
    if (!on || file == nullptr || *file == '\0' || totals.empty()) return;
    std::ofstream out(file);
    out << team_profile_table(team_profile_totals());
    if (!out) std::fprintf(stderr, "deli: %s: cannot write the team profile\n", file);
  }
};

Profile& profile() {
  static Profile p;
  return p;
}

}  // namespace

bool team_profile_on() {
  return profile().on;
}

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

void set_team_profile(bool on) {
  Profile& p = profile();
  p.on = on;
  p.totals.clear();
  p.last_done_ns = -1;
  p.recording = true;
}

void team_profile_loop_started() {
  Profile& p = profile();
  if (!p.on) return;
  p.totals.clear();
  p.last_done_ns = steady_ns();
  p.recording = true;
}

void team_profile_loop_ended() {
  profile().recording = false;
}

void team_profile_record(const void* job, std::int64_t start_ns, std::int64_t own_done_ns,
                         std::int64_t done_ns, std::int64_t slowest_worker_ns) {
  Profile& p = profile();
  if (!p.recording) return;
  JobTotals& t = p.totals[job];
  t.job = job;
  ++t.calls;
  t.own_ns += own_done_ns - start_ns;
  t.wait_ns += done_ns - own_done_ns;
  t.slowest_worker_ns += slowest_worker_ns;
  if (p.last_done_ns >= 0) t.serial_before_ns += start_ns - p.last_done_ns;
  p.last_done_ns = done_ns;
}

std::vector<JobTotals> team_profile_totals() {
  std::vector<JobTotals> out;
  for (const auto& [job, totals] : profile().totals) out.push_back(totals);
  std::sort(out.begin(), out.end(), [](const JobTotals& a, const JobTotals& b) {
    return a.own_ns + a.wait_ns > b.own_ns + b.wait_ns;
  });
  return out;
}

std::string team_profile_table(const std::vector<JobTotals>& totals) {
  std::string table =
      "# calls, then milliseconds: own (the calling thread's chunks), wait (for the "
      "workers), slowest worker, serial before; the job's function: object file, offset\n";
  char line[512];
  for (const JobTotals& t : totals) {
    Dl_info info{};
    const bool found = dladdr(t.job, &info) != 0 && info.dli_fname != nullptr;
    const auto offset = reinterpret_cast<std::uintptr_t>(t.job) -
                        (found ? reinterpret_cast<std::uintptr_t>(info.dli_fbase) : 0);
    std::snprintf(line, sizeof line, "%lld %.3f %.3f %.3f %.3f %s 0x%llx\n",
                  static_cast<long long>(t.calls), t.own_ns * 1e-6, t.wait_ns * 1e-6,
                  t.slowest_worker_ns * 1e-6, t.serial_before_ns * 1e-6,
                  found ? info.dli_fname : "?", static_cast<unsigned long long>(offset));
    table += line;
  }
  return table;
}

}  // namespace deli
