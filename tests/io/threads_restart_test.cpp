// `deli run --threads 2`: the same input on two threads twice, and stopped at a checkpoint
// and restarted, gives the same thermo rows bit for bit; on one thread it gives the same
// rows to round-off (the sums are regrouped). The one-thread rows are the expected values.
// The same with [run] split_small_loops = false (the 4000 atoms' passes on one thread, as by
// default until stop 49). The thread count where the process may use fewer CPUs than asked
// for (its affinity mask, a cgroup's CPU quota).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/csv_numbers.hpp"
#include "support/file_contents.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"
#include "support/short_runs.hpp"

namespace deli {
namespace {

// The harmonic chain melt (pairs, bonds, exclusions: 4000 atoms) under a Langevin
// thermostat, with thermo rows every 10 steps and a checkpoint every 60.
std::string melt_input(const std::string& dir, int steps, const std::string& run_extra) {
  std::string text =
      testing::file_contents(DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000_harmonic.toml");
  text = text.substr(0, text.find("[run]"));
  text.replace(text.find("\"chains_4000.data\""), 18,
               "\"" DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000.data\"");
  const std::string path = dir + "/run" + std::to_string(steps) + ".toml";
  std::ofstream(path) << text << "[thermostat]\ntype = \"langevin\"\ntemperature = 1.2\n"
                      << "damping = 1.0\nseed = 5\n[run]\nsteps = " << steps << "\n"
                      << run_extra << "[output]\n"
                      << "thermo = { every = 10, file = \"" << dir << "/out.csv\" }\n"
                      << "checkpoint = { file = \"" << dir << "/out.chk\", every = 60 }\n";
  return path;
}

// Waiting threads sleep (OMP_WAIT_POLICY=passive): ctest runs another test beside this one
// on two cores, and a thread spinning at a barrier takes the core its partner needs (81 s
// against 3.5 s, measured under load).
std::string run_melt(const std::string& dir, int steps, const std::string& extra,
                     const std::string& run_extra = "") {
  testing::run_shell("mkdir -p " + dir);
  const testing::ShellResult r =
      testing::run_shell("OMP_WAIT_POLICY=passive " DELI_BINARY " run " +
                         melt_input(dir, steps, run_extra) + " " + extra);
  EXPECT_EQ(r.status, 0) << r.output;
  if (extra.find("--threads 2") != std::string::npos) {
    const bool unsplit = run_extra.find("split_small_loops = false") != std::string::npos;
    EXPECT_EQ(r.output.find("2 threads (small loops not split)") != std::string::npos, unsplit)
        << r.output;
  }
  return testing::file_contents(dir + "/out.csv");
}

void expect_repeat_and_restart_bit_for_bit(const std::string& name, const std::string& run_extra) {
  const std::string root =
      deli::testing::process_temp_dir() + "/" + name + "_" + std::to_string(getpid());
  // Under the sanitizers (support/short_runs.hpp) 40 steps, stopped at 30: the same code
  // (threaded loops, checkpoint, restart) on a third of the steps.
  const int steps = testing::steps_or_prefix(120, 40), stop = testing::steps_or_prefix(90, 30);
  const std::string straight = run_melt(root + "/straight", steps, "--threads 2", run_extra);
  EXPECT_EQ(straight, run_melt(root + "/again", steps, "--threads 2", run_extra));
  run_melt(root + "/stopped", stop, "--threads 2", run_extra);
  const std::string restarted = run_melt(
      root + "/stopped", steps, "--threads 2 --restart " + root + "/stopped/out.chk", run_extra);
  EXPECT_EQ(straight, restarted);

  // One thread: every column within 1e-8 relative of its scale after 120 steps (round-off
  // of the regrouped sums, grown by the dynamics' chaos).
  const auto a = testing::csv_numbers(straight),
             b = testing::csv_numbers(run_melt(root + "/one", steps, "--threads 1", run_extra));
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), static_cast<std::size_t>(steps / 10 + 1));
  for (std::size_t r = 0; r < a.size(); ++r) {
    ASSERT_EQ(a[r].size(), b[r].size());
    for (std::size_t c = 0; c < a[r].size(); ++c) {
      EXPECT_NEAR(a[r][c], b[r][c], 1e-8 * (1.0 + std::abs(b[r][c])))
          << "row " << r << " col " << c;
    }
  }
  testing::run_shell("rm -rf " + root);
}

TEST(ThreadsRun, TwoThreadsRepeatAndRestartBitForBit) {
  expect_repeat_and_restart_bit_for_bit("threads_restart", "");
}

TEST(ThreadsRun, SmallLoopsUnsplitRepeatAndRestartBitForBit) {
  expect_repeat_and_restart_bit_for_bit("threads_unsplit_restart", "split_small_loops = false\n");
}

// More threads than the CPUs the process may use (pinned to one by taskset): the header says
// so, and the threads, waiting without spinning, make the trajectory of as many threads on
// as many CPUs, bit for bit (a run's chunks depend on its thread count alone).
TEST(ThreadsRun, MoreThreadsThanCpusSaySoAndRunTheSameTrajectory) {
  const std::string root =
      deli::testing::process_temp_dir() + "/threads_crowded_" + std::to_string(getpid());
  const int steps = 20;
  testing::run_shell("mkdir -p " + root + "/crowded " + root + "/free");
  const testing::ShellResult crowded =
      testing::run_shell("taskset -c 0 " DELI_BINARY " run " +
                         melt_input(root + "/crowded", steps, "") + " --threads 2");
  ASSERT_EQ(crowded.status, 0) << crowded.output;
  EXPECT_NE(crowded.output.find("note: 2 threads on 1 CPU this process may use"), std::string::npos)
      << crowded.output;
  const std::string free_run = run_melt(root + "/free", steps, "--threads 2");
  EXPECT_EQ(testing::file_contents(root + "/crowded/out.csv"), free_run);
  testing::run_shell("rm -rf " + root);
}

// A cgroup of its own with a CPU quota of 1 CPU (v1's cpu.cfs_quota_us, or v2's cpu.max where
// the cpu controller is enabled there), made under the first cgroup file system with the cpu
// controller, and removed with it; empty where none can be made (not root, cgroups read-only,
// as in many containers).
class QuotaCgroup {
 public:
  QuotaCgroup() {
    std::ifstream mounts("/proc/self/mountinfo");
    std::string line;
    while (dir_.empty() && std::getline(mounts, line)) {
      std::istringstream in(line);
      std::vector<std::string> f;
      for (std::string word; in >> word;) f.push_back(word);
      const auto dash = std::find(f.begin(), f.end(), "-");
      if (f.size() < 5 || f.end() - dash < 4) continue;
      const bool v2 = dash[1] == "cgroup2";
      const bool v1 =
          dash[1] == "cgroup" && ("," + dash[3] + ",").find(",cpu,") != std::string::npos;
      if (!v1 && !v2) continue;
      const std::string dir = f[4] + "/deli-test-" + std::to_string(getpid());
      if (::mkdir(dir.c_str(), 0755) != 0) continue;
      const std::string file = dir + (v2 ? "/cpu.max" : "/cpu.cfs_quota_us");
      const std::string period = dir + "/cpu.cfs_period_us";
      std::ofstream quota(file);
      if (quota && (v2 || std::ifstream(period)) &&
          (quota << (v2 ? "100000 100000" : "100000") << std::flush)) {
        dir_ = dir;
      } else {
        ::rmdir(dir.c_str());
      }
    }
  }
  QuotaCgroup(const QuotaCgroup&) = delete;
  QuotaCgroup& operator=(const QuotaCgroup&) = delete;
  ~QuotaCgroup() {
    if (!dir_.empty()) ::rmdir(dir_.c_str());
  }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
};

// With no count asked for, a run in a cgroup whose quota is 1 CPU runs 1 thread and says why;
// asked for 2 there, it runs 2 and says that 1 is likely faster (README, "A container's CPU
// quota"). On two CPUs of the affinity mask (taskset), where OpenMP's default is 2.
TEST(ThreadsRun, DefaultThreadsKeepWithinTheCgroupsCpuQuota) {
  if (::sysconf(_SC_NPROCESSORS_ONLN) < 2) GTEST_SKIP() << "needs two CPUs";
  const QuotaCgroup cgroup;
  if (cgroup.dir().empty()) GTEST_SKIP() << "no cgroup with a CPU quota can be made here";
  const std::string root =
      deli::testing::process_temp_dir() + "/threads_quota_" + std::to_string(getpid());
  testing::run_shell("mkdir -p " + root);
  const std::string input = melt_input(root, 2, "");
  auto in_cgroup = [&](const std::string& extra) {
    return testing::run_shell("env -u OMP_NUM_THREADS sh -c 'echo $$ > " + cgroup.dir() +
                              "/cgroup.procs && exec taskset -c 0,1 " DELI_BINARY " run " + input +
                              extra + "'");
  };
  const testing::ShellResult by_default = in_cgroup("");
  ASSERT_EQ(by_default.status, 0) << by_default.output;
  EXPECT_NE(by_default.output.find("note: this process's cgroup has a CPU quota of 1 CPU: 1 "
                                   "thread by default"),
            std::string::npos)
      << by_default.output;
  EXPECT_NE(by_default.output.find("\n1 thread\n"), std::string::npos) << by_default.output;
  const testing::ShellResult asked = in_cgroup(" --threads 2");
  ASSERT_EQ(asked.status, 0) << asked.output;
  EXPECT_NE(asked.output.find("\n2 threads\n"), std::string::npos) << asked.output;
  EXPECT_NE(asked.output.find("note: 2 threads in a cgroup whose CPU quota is 1 CPU"),
            std::string::npos)
      << asked.output;
  testing::run_shell("rm -rf " + root);
}

}  // namespace
}  // namespace deli
