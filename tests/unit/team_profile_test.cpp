// The team profile's accounting (core/team_profile.hpp): a job whose chunks sleep for known
// times shows at least those times where the definitions put them (sleep_for waits at
// least as long as asked; the bounds are those sleeps, nothing measured).
#include "core/team_profile.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/thread_team.hpp"

namespace deli {
namespace {

constexpr std::int64_t kMs = 1000000;

void sleep_ms(int ms) {
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
}

// Chunk 0 (the calling thread) sleeps 3 ms, chunk 1 (a worker) nothing.
void caller_sleeps(void*, int thread, int) {
  if (thread == 0) sleep_ms(3);
}
// Chunk 1 sleeps 3 ms, chunk 0 nothing.
void worker_sleeps(void*, int thread, int) {
  if (thread == 1) sleep_ms(3);
}

const JobTotals* totals_of(const std::vector<JobTotals>& all, TeamJob job) {
  for (const JobTotals& t : all) {
    if (t.job == reinterpret_cast<const void*>(job)) return &t;
  }
  return nullptr;
}

TEST(TeamProfile, EachJobsTimeGoesWhereItWasSpent) {
  set_team_profile(true);
  run_on_team(2, caller_sleeps, nullptr);
  sleep_ms(2);  // serial work between the jobs
  run_on_team(2, worker_sleeps, nullptr);
  run_on_team(2, worker_sleeps, nullptr);
  const std::vector<JobTotals> all = team_profile_totals();
  set_team_profile(false);
  const JobTotals* caller = totals_of(all, caller_sleeps);
  const JobTotals* worker = totals_of(all, worker_sleeps);
  ASSERT_NE(caller, nullptr);
  ASSERT_NE(worker, nullptr);
  EXPECT_EQ(caller->calls, 1);
  EXPECT_EQ(worker->calls, 2);
  EXPECT_GE(caller->own_ns, 3 * kMs);
  // The worker's sleeps: its chunks, and the calling thread's waits for them (its own chunk
  // empty).
  EXPECT_GE(worker->slowest_worker_ns, 2 * 3 * kMs);
  EXPECT_GE(worker->own_ns + worker->wait_ns, 2 * 3 * kMs);
  // The 2 ms between the first and second job: serial time before the second kind.
  EXPECT_GE(worker->serial_before_ns, 2 * kMs);
  // The totals come in order of the calling thread's time: 6 ms and more before 3 ms.
  EXPECT_EQ(all.front().job, reinterpret_cast<const void*>(&worker_sleeps));
}

// Scoped to a step loop (as run() scopes it): the jobs before its start and after its end are
// not in the totals, and the serial time before the loop's first job counts from its start.
TEST(TeamProfile, AStepLoopsTotalsHoldItsJobsAlone) {
  set_team_profile(true);
  run_on_team(2, worker_sleeps, nullptr);  // the set-up's
  team_profile_loop_started();
  sleep_ms(2);
  run_on_team(2, caller_sleeps, nullptr);
  team_profile_loop_ended();
  run_on_team(2, worker_sleeps, nullptr);  // the final output's
  const std::vector<JobTotals> all = team_profile_totals();
  set_team_profile(false);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all.front().job, reinterpret_cast<const void*>(&caller_sleeps));
  EXPECT_EQ(all.front().calls, 1);
  EXPECT_GE(all.front().serial_before_ns, 2 * kMs);
}

TEST(TeamProfile, OffRecordsNothing) {
  set_team_profile(false);
  run_on_team(2, worker_sleeps, nullptr);
  EXPECT_TRUE(team_profile_totals().empty());
}

TEST(TeamProfile, TheTableNamesEachJobsObjectAndOffset) {
  set_team_profile(true);
  run_on_team(2, caller_sleeps, nullptr);
  const std::string table = team_profile_table(team_profile_totals());
  set_team_profile(false);
  // A header, then one line: "1 <own> <wait> <worker> <serial> <object> 0x<offset>".
  const std::size_t line = table.find('\n') + 1;
  ASSERT_LT(line, table.size());
  EXPECT_EQ(table.compare(line, 2, "1 "), 0) << table;
  EXPECT_NE(table.find("deli_unit_tests 0x", line), std::string::npos) << table;
}

}  // namespace
}  // namespace deli
