#include "core/thread_team.hpp"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

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

const WaitPolicy& wait_policy() {
  static const WaitPolicy policy = wait_policy_from_environment();
  return policy;
}

// Waits until done(): spins, then yields its core between looks.
template <class Done>
void spin_until(Done&& done) {
  const int before_yield = wait_policy().spins_before_yield;
  int spins = 0;
  while (!done()) {
    if (spins < before_yield) {
      ++spins;
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

class Team {
 public:
  ~Team() {
    {
      std::lock_guard<std::mutex> lock(sleep_mutex_);
      stop_.store(true, std::memory_order_seq_cst);
      generation_.fetch_add(1, std::memory_order_seq_cst);
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

  void run(int threads, TeamJob job, void* context) {
    std::lock_guard<std::mutex> one_job(run_mutex_);
    while (static_cast<int>(workers_.size()) < threads - 1) {
      const int index = static_cast<int>(workers_.size()) + 1;
      const std::uint64_t seen = generation_.load(std::memory_order_relaxed);
      workers_.emplace_back([this, index, seen] { work(index, seen); });
    }
    job_ = job;
    context_ = context;
    threads_ = threads;
    arrived_.store(0, std::memory_order_relaxed);
    // Every worker acknowledges every job (those beyond `threads` without running it), so
    // that none can read a later job's fields while taking an earlier one.
    remaining_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
    // seq_cst with the sleepers' count (and theirs the other way round): either a worker
    // going to sleep sees the new generation, or this sees it asleep and wakes it.
    generation_.fetch_add(1, std::memory_order_seq_cst);
    if (sleepers_.load(std::memory_order_seq_cst) > 0) {
      std::lock_guard<std::mutex> lock(sleep_mutex_);
      wake_.notify_all();
    }
    enter(0, threads);
    job(context, 0, threads);
    leave();
    spin_until([&] { return remaining_.load(std::memory_order_acquire) == 0; });
  }

  void barrier() {
    const std::uint64_t phase = barrier_phase_.load(std::memory_order_acquire);
    if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == threads_) {
      arrived_.store(0, std::memory_order_relaxed);
      barrier_phase_.store(phase + 1, std::memory_order_release);
      return;
    }
    spin_until([&] { return barrier_phase_.load(std::memory_order_acquire) != phase; });
  }

 private:
  static void enter(int thread, int threads) {
    in_job = true;
    job_thread = thread;
    job_threads = threads;
  }
  static void leave() {
    in_job = false;
    job_thread = 0;
    job_threads = 1;
  }

  void work(int index, std::uint64_t seen) {
    for (;;) {
      const int before_sleep = wait_policy().spins_before_sleep;
      int spins = 0;
      while (generation_.load(std::memory_order_acquire) == seen) {
        if (before_sleep < 0) {
          spin_pause();
          continue;
        }
        if (spins < before_sleep) {
          ++spins;
          spin_pause();
          continue;
        }
        std::unique_lock<std::mutex> lock(sleep_mutex_);
        sleepers_.fetch_add(1, std::memory_order_seq_cst);
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_seq_cst) != seen; });
        sleepers_.fetch_sub(1, std::memory_order_seq_cst);
      }
      seen = generation_.load(std::memory_order_acquire);
      if (stop_.load(std::memory_order_acquire)) return;
      if (index < threads_) {
        enter(index, threads_);
        job_(context_, index, threads_);
        leave();
      }
      remaining_.fetch_sub(1, std::memory_order_acq_rel);
    }
  }

  std::mutex run_mutex_;
  std::vector<std::thread> workers_;
  // The job, written before the generation is advanced and read after it is seen.
  TeamJob job_ = nullptr;
  void* context_ = nullptr;
  int threads_ = 1;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<int> remaining_{0};
  std::atomic<int> arrived_{0};
  std::atomic<std::uint64_t> barrier_phase_{0};
  std::atomic<int> sleepers_{0};
  std::atomic<bool> stop_{false};
  std::mutex sleep_mutex_;
  std::condition_variable wake_;
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
  team().barrier();
}

int team_thread() {
  return job_thread;
}

}  // namespace deli
