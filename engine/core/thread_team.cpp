#include "core/thread_team.hpp"

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/chunk_balance.hpp"
#include "core/cpu_pressure.hpp"
#include "core/team_profile.hpp"

namespace deli {

namespace {

void spin_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// How long threads wait by spinning, as OpenMP's OMP_WAIT_POLICY asks: unset, a worker waiting
// for work spins a few milliseconds (libgomp's default spins about as long, far more than the
// gaps between a step's loops) before it sleeps, and a thread waiting for the others' chunks
// or at a barrier yields its core between looks past a quarter of that (a thread it waits for
// may have lost its core, as where processes outnumber the cores); `passive`: neither spins
// (workers sleep at once, waiters yield), for machines whose cores have other work; `active`:
// workers never sleep.
struct WaitPolicy {
  int spins_before_sleep = 1 << 17;  // a worker waiting for work; -1: never sleeps
  int spins_before_yield = 1 << 15;  // a thread waiting within a job
};

WaitPolicy wait_policy_from_environment() {
  WaitPolicy policy;
  const char* asked = std::getenv("OMP_WAIT_POLICY");
  const std::string value = asked ? asked : "";
  if (value == "passive" || value == "PASSIVE") {
    policy.spins_before_sleep = 0;
    policy.spins_before_yield = 0;
  } else if (value == "active" || value == "ACTIVE") {
    policy.spins_before_sleep = -1;
  }
  return policy;
}

// Other processes' threads on this process's CPUs: a thread that has waited within a job
// for longer than kWait (the imbalance of a job's chunks is microseconds) while the system's
// threads waited for a CPU more than a third of the time (stall_means_crowded) has waited for
// a thread of its job that lost its CPU to another process, and then the process waits as
// `passive` for kSpell before it spins again. Two 2-thread runs of the 4000-sphere fluid at
// once on this 2-core machine took 0.7-25 s each (0.29 s alone), every job's wait a time
// slice of the scheduler while the other process's threads spun or yielded; as `passive`,
// 1.1-1.6 s. Without the stall test, a virtual machine whose host takes the CPU away makes
// long waits too (2 % stall in the fluid's run with the cores far apart, against 55-99 % in
// 50 ms windows beside a second run), where sleeping hands the CPU to no one and adds each
// job's wake-up (that fluid on two threads 1.8x slower). A run alone stalls briefly too, where
// a kernel thread or a light process wakes while the team spins on every CPU: up to 25 % of a
// 50 ms window and 12 % of a 100 ms one on this machine, which at a tenth sent 11 of 81
// 200-step runs of the 32000-sphere fluid alone passive (up to 1.4x their time). The
// stall is read at most every kCheck, and compared only with a reading less than a second old.
class CrowdWatch {
 public:
  static constexpr std::int64_t kWait = 200'000;            // ns
  static constexpr std::int64_t kSpell = 1'000'000'000;     // ns
  static constexpr std::int64_t kCheck = 50'000'000;        // ns
  static constexpr std::int64_t kStallAge = 1'000'000'000;  // ns

  bool crowded() {
    if (!crowded_.load(std::memory_order_relaxed)) return false;
    if (steady_ns() < until_.load(std::memory_order_relaxed)) return true;
    crowded_.store(false, std::memory_order_relaxed);
    return false;
  }
  // Whether a spell is on now, without ending one that is over.
  bool in_spell() const { return crowded_.load(std::memory_order_relaxed); }
  // A wait within a job that began at `since` goes on at `now`.
  void waited(std::int64_t since, std::int64_t now) {
    if (now - since <= kWait || !stall_high(now)) return;
    until_.store(now + kSpell, std::memory_order_relaxed);
    if (!crowded_.exchange(true, std::memory_order_relaxed)) {
      spells_.fetch_add(1, std::memory_order_relaxed);
    }
  }
  long long spells() const { return spells_.load(std::memory_order_relaxed); }

 private:
  bool stall_high(std::int64_t now) {
    std::unique_lock<std::mutex> lock(stall_mutex_, std::try_to_lock);
    if (!lock || now - stall_seen_at_ < kCheck) return false;
    const std::optional<long long> total = cpu_stall_total_us();
    const bool high = stall_seen_ && total && now - stall_seen_at_ < kStallAge &&
                      stall_means_crowded(*total - *stall_seen_, now - stall_seen_at_);
    stall_seen_at_ = now;
    stall_seen_ = total;
    return high;
  }

  std::atomic<bool> crowded_{false};
  std::atomic<std::int64_t> until_{0};
  std::atomic<long long> spells_{0};
  std::mutex stall_mutex_;
  std::int64_t stall_seen_at_ = 0;       // ns
  std::optional<long long> stall_seen_;  // us
};

CrowdWatch& crowd_watch() {
  static CrowdWatch watch;
  return watch;
}

// The policy for a job of `threads` threads. With more threads than CPUs to run them, a
// spinning thread holds a CPU that a thread with work is queued for, until the scheduler's
// time slice ends (milliseconds): the default input on 4 threads on this 2-core machine took
// 382 s for 3000 steps, against 1.8 s on 2. There nothing spins: workers sleep at once and
// waiters yield, as `passive` (libgomp likewise throttles its spinning past the CPU count);
// `active` still keeps workers awake, as asked. The same while other processes crowd the
// CPUs (CrowdWatch).
const WaitPolicy& wait_policy(int threads) {
  static const WaitPolicy asked = wait_policy_from_environment();
  static const WaitPolicy crowded{asked.spins_before_sleep < 0 ? -1 : 0, 0};
  return threads > cpus_available() || crowd_watch().crowded() ? crowded : asked;
}

// Waits until done(), within a job of `threads` threads: spins, then yields its core between
// looks. A wait still going after kSpinsBeforeClock spins (tens of microseconds) is timed
// from there (CrowdWatch).
template <class Done>
void spin_until(int threads, Done&& done) {
  constexpr int kSpinsBeforeClock = 1024, kLooksBetweenClocks = 256;
  const int before_yield = wait_policy(threads).spins_before_yield;
  CrowdWatch& watch = crowd_watch();
  std::int64_t looks = 0;
  std::int64_t since = 0;
  while (!done()) {
    ++looks;
    if (looks >= kSpinsBeforeClock && looks % kLooksBetweenClocks == 0 && !watch.in_spell()) {
      const std::int64_t now = steady_ns();
      if (since == 0) {
        since = now;
      } else {
        watch.waited(since, now);
      }
    }
    if (looks < before_yield && !watch.in_spell()) {
      spin_pause();
    } else {
      std::this_thread::yield();
    }
  }
}

// The job the calling thread is in: its number and its job's thread count.
thread_local int job_thread = 0;
thread_local int job_threads = 1;
thread_local bool in_job = false;
// Whether the running job's busy time is measured for the chunks' shares, and this thread's
// waits at its barriers so far (left out of its busy time).
thread_local bool job_measured = false;
thread_local std::int64_t barrier_wait_ns = 0;

// One worker thread and what the calling thread posts to it alone: a job is posted only to the
// workers it runs on (threads 1..threads-1 of the job), so that a job of fewer chunks than the
// team has threads wakes no other worker. The job's fields share the post's cache line, and
// the worker's count of jobs done has a line of its own that only the worker writes: where the
// cores are far apart (a cache line's round trip of 400 ns) each line the worker reads after
// the calling thread wrote it, or the calling thread after the worker, is a round trip on the
// job's path (the job's fields on the team's line, a count of workers still running that both
// sides wrote: an empty job 1.1 us there, bench/README.md, "Stop 53").
struct alignas(64) Worker {
  // Written by the calling thread before the post, read by the worker after it.
  TeamJob job = nullptr;
  void* context = nullptr;
  int threads = 1;
  bool measured = false;  // chunk_balance_measures() for this job
  std::atomic<bool> asleep{false};
  std::atomic<std::uint64_t> posted{0};            // jobs posted to this worker
  alignas(64) std::atomic<std::uint64_t> done{0};  // jobs it has finished
  std::int64_t job_ns = 0;  // its last job's time, with the team profile on (before `done`)
  alignas(64) std::mutex sleep_mutex;
  std::condition_variable wake;
  std::thread thread;
};

class Team {
 public:
  ~Team() {
    stop_.store(true, std::memory_order_seq_cst);
    for (auto& w : workers_) post(*w);
    for (auto& w : workers_) w->thread.join();
  }

  void run(int threads, TeamJob job, void* context) {
    std::lock_guard<std::mutex> one_job(run_mutex_);
    while (static_cast<int>(workers_.size()) < threads - 1) {
      const int index = static_cast<int>(workers_.size()) + 1;
      workers_.push_back(std::make_unique<Worker>());
      Worker& w = *workers_.back();
      w.thread = std::thread([this, index, &w] { work(index, w); });
    }
    // A worker reads its job's fields after their post, and finished the last job it was
    // posted before this thread returned from it (below).
    const bool measured = chunk_balance_measures(threads);
    for (int t = 1; t < threads; ++t) {
      Worker& w = *workers_[static_cast<std::size_t>(t - 1)];
      w.job = job;
      w.context = context;
      w.threads = threads;
      w.measured = measured;
      post(w);
    }
    const bool profiled = team_profile_on();
    const std::int64_t start = profiled || measured ? steady_ns() : 0;
    enter(0, threads, measured);
    job(context, 0, threads);
    const std::int64_t waited = leave();
    const std::int64_t own_done = profiled || measured ? steady_ns() : 0;
    if (measured) add_balanced_busy(0, own_done - start - waited);
    std::int64_t slowest_worker = 0;
    for (int t = 1; t < threads; ++t) {
      const Worker& w = *workers_[static_cast<std::size_t>(t - 1)];
      const std::uint64_t posted = w.posted.load(std::memory_order_relaxed);
      spin_until(threads, [&] { return w.done.load(std::memory_order_acquire) == posted; });
      slowest_worker = std::max(slowest_worker, w.job_ns);
    }
    if (profiled) {
      team_profile_record(reinterpret_cast<const void*>(job), start, own_done, steady_ns(),
                          slowest_worker);
    }
  }

  // `threads`: the job's. The last to arrive sets the count back to zero before it lets the
  // others go, so every barrier, and every job, starts from zero.
  void barrier(int threads) {
    const std::uint64_t phase = barrier_phase_.load(std::memory_order_acquire);
    if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == threads) {
      arrived_.store(0, std::memory_order_relaxed);
      barrier_phase_.store(phase + 1, std::memory_order_release);
      return;
    }
    const std::int64_t start = job_measured ? steady_ns() : 0;
    spin_until(threads, [&] { return barrier_phase_.load(std::memory_order_acquire) != phase; });
    if (job_measured) barrier_wait_ns += steady_ns() - start;
  }

 private:
  static void enter(int thread, int threads, bool measured) {
    in_job = true;
    job_thread = thread;
    job_threads = threads;
    job_measured = measured;
    barrier_wait_ns = 0;
  }
  // Returns the thread's waits at the job's barriers where the job was measured.
  static std::int64_t leave() {
    in_job = false;
    job_thread = 0;
    job_threads = 1;
    job_measured = false;
    return barrier_wait_ns;
  }

  // seq_cst with the worker's `asleep` (and the worker's the other way round): either the
  // worker going to sleep sees the post, or this sees it asleep and wakes it.
  static void post(Worker& w) {
    w.posted.fetch_add(1, std::memory_order_seq_cst);
    if (w.asleep.load(std::memory_order_seq_cst)) {
      std::lock_guard<std::mutex> lock(w.sleep_mutex);
      w.wake.notify_one();
    }
  }

  void work(int index, Worker& w) {
    std::uint64_t seen = 0;
    int last_threads = 1;  // the last job's
    for (;;) {
      const int before_sleep = wait_policy(last_threads).spins_before_sleep;
      int spins = 0;
      while (w.posted.load(std::memory_order_acquire) == seen) {
        if (before_sleep < 0) {
          spin_pause();
          continue;
        }
        if (spins < before_sleep) {
          ++spins;
          spin_pause();
          continue;
        }
        std::unique_lock<std::mutex> lock(w.sleep_mutex);
        w.asleep.store(true, std::memory_order_seq_cst);
        w.wake.wait(lock, [&] { return w.posted.load(std::memory_order_seq_cst) != seen; });
        w.asleep.store(false, std::memory_order_seq_cst);
      }
      seen = w.posted.load(std::memory_order_acquire);
      if (stop_.load(std::memory_order_acquire)) return;
      last_threads = w.threads;
      const bool profiled = team_profile_on();
      const bool measured = w.measured;
      const std::int64_t start = profiled || measured ? steady_ns() : 0;
      enter(index, last_threads, measured);
      w.job(w.context, index, last_threads);
      const std::int64_t waited = leave();
      const std::int64_t end = profiled || measured ? steady_ns() : 0;
      w.job_ns = profiled ? end - start : 0;
      if (measured) add_balanced_busy(index, end - start - waited);
      w.done.store(seen, std::memory_order_release);
    }
  }

  std::mutex run_mutex_;
  std::vector<std::unique_ptr<Worker>> workers_;
  // Barriers within a job (their own line: written only by them).
  alignas(64) std::atomic<int> arrived_{0};
  std::atomic<std::uint64_t> barrier_phase_{0};
  // Read by the workers at every job, written once.
  alignas(64) std::atomic<bool> stop_{false};
};

Team& team() {
  static Team t;
  return t;
}

}  // namespace

void run_on_team(int threads, TeamJob job, void* context) {
  if (threads <= 1 || in_job) {
    const bool was_in = in_job;
    const int thread = job_thread, count = job_threads;
    in_job = true;
    job_thread = 0;
    job_threads = 1;
    job(context, 0, 1);
    in_job = was_in;
    job_thread = thread;
    job_threads = count;
    return;
  }
  team().run(threads, job, context);
}

void team_barrier() {
  if (!in_job || job_threads <= 1) return;
  team().barrier(job_threads);
}

int team_thread() {
  return job_thread;
}

long long crowded_spells() {
  return crowd_watch().spells();
}

int cpus_available() {
  static const int cpus = [] {
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  }();
  return cpus;
}

}  // namespace deli
