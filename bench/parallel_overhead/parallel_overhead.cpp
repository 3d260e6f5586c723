// What deli's threading costs per call on this machine (Google Benchmark; not a test), with
// 2 threads unless OMP_NUM_THREADS says otherwise: an empty chunked loop (for_each_chunk, on
// deli's team) and an empty OpenMP parallel region, a barrier inside one job of the team and
// inside one OpenMP region, and a cheap pass over 4000
// particles (a kick: p += f h/2, as GVI's and velocity Verlet's per-particle passes) on the
// calling thread alone and split into chunks. A pass of a few microseconds gains from a
// second thread only where the split saves more than a region costs. And what moving data
// between the threads' cores costs: a cache line handed back and forth, and the chunked
// kick with the chunks' owners swapped every pass (each pass reads the lines the other
// core wrote last), against the same kick with the chunks kept; per line, reads of many
// lines the other core wrote last (in order and shuffled) and stores to lines it read; a
// step's exchange of two halves as a 4000-particle box's pair loop makes it; and how much the
// same fixed work's time wanders from call to call, and between two threads within a call
// (what a loop of fixed chunks loses at its end, whatever its code).
//   cmake --build build --target deli-parallel-overhead
//   OMP_NUM_THREADS=2 build/bench/parallel_overhead/deli-parallel-overhead
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <random>
#include <vector>

#include "core/cache_line.hpp"
#include "core/parallel.hpp"
#include "core/thread_team.hpp"
#include "core/vec3.hpp"

namespace deli {
namespace {

constexpr std::size_t kParticles = 4000;

int threads() {
  return std::max(2, thread_count());
}

void EmptyRegion(benchmark::State& state) {
  const int chunks = threads();
  for (auto _ : state) {
    for_each_chunk(kParticles, chunks,
                   [](int c, std::size_t, std::size_t) { benchmark::DoNotOptimize(c); });
  }
}
BENCHMARK(EmptyRegion)->UseRealTime();

// An empty job of two threads on a team grown to four (the team of a larger machine running a
// loop of two chunks: the default input's particle passes on more than two cores), against
// EmptyRegion's team of two: whether the workers a job does not run on cost it anything.
void EmptyJobOfTwoOnATeamOfFour(benchmark::State& state) {
  auto nothing = [](int t, int) { benchmark::DoNotOptimize(t); };
  run_on_team(4, nothing);
  for (auto _ : state) run_on_team(2, nothing);
}
BENCHMARK(EmptyJobOfTwoOnATeamOfFour)->UseRealTime();

// The same empty loop as an OpenMP parallel region, as deli's loops ran before they ran on
// their own team (core/thread_team.hpp): libgomp ends each of its two barriers with a futex
// system call.
void EmptyOpenMpRegion(benchmark::State& state) {
  const int chunks = threads();
  for (auto _ : state) {
#pragma omp parallel num_threads(chunks)
    benchmark::DoNotOptimize(omp_get_thread_num());
  }
}
BENCHMARK(EmptyOpenMpRegion)->UseRealTime();

// Barriers inside one job of deli's team (for_each_chunk_then's between its passes).
void TeamBarrier(benchmark::State& state) {
  const int chunks = threads();
  const auto per_job = static_cast<std::int64_t>(1000);
  for (auto _ : state) {
    auto job = [&](int, int) {
      for (std::int64_t k = 0; k < per_job; ++k) team_barrier();
    };
    run_on_team(chunks, job);
  }
  state.counters["per_barrier"] = benchmark::Counter(
      static_cast<double>(per_job),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(TeamBarrier)->UseRealTime();

// OpenMP barriers inside one region, as a step kept in one region would meet between its
// phases.
void Barrier(benchmark::State& state) {
  const int chunks = threads();
  const auto per_region = static_cast<std::int64_t>(1000);
  for (auto _ : state) {
#pragma omp parallel num_threads(chunks)
    for (std::int64_t k = 0; k < per_region; ++k) {
#pragma omp barrier
    }
  }
  // Seconds per barrier.
  state.counters["per_barrier"] = benchmark::Counter(
      static_cast<double>(per_region),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(Barrier)->UseRealTime();

struct Kick {
  std::vector<Vec3> p = std::vector<Vec3>(kParticles, Vec3{1.0, 2.0, 3.0});
  std::vector<Vec3> f = std::vector<Vec3>(kParticles, Vec3{0.5, -0.5, 0.25});
  void pass(std::size_t begin, std::size_t end) {
    const double half = 0.0025;
    for (std::size_t i = begin; i < end; ++i) p[i] += f[i] * half;
  }
};

void KickOneThread(benchmark::State& state) {
  Kick kick;
  for (auto _ : state) {
    kick.pass(0, kParticles);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(KickOneThread)->UseRealTime();

void KickInChunks(benchmark::State& state) {
  Kick kick;
  const int chunks = threads();
  for (auto _ : state) {
    for_each_chunk(kParticles, chunks,
                   [&](int, std::size_t begin, std::size_t end) { kick.pass(begin, end); });
    benchmark::ClobberMemory();
  }
}
BENCHMARK(KickInChunks)->UseRealTime();

// Two threads hand one cache line back and forth: the time of a round trip, twice what a
// line written on one core costs the other core to read.
void CacheLineRoundTrip(benchmark::State& state) {
  constexpr std::int64_t kTrips = 10000;
  alignas(64) std::atomic<std::int64_t> turn{0};
  for (auto _ : state) {
    turn.store(0);
#pragma omp parallel num_threads(2)
    {
      const std::int64_t me = omp_get_thread_num();
      if (me < 2 && omp_get_num_threads() == 2) {
        for (std::int64_t k = me; k < 2 * kTrips; k += 2) {
          while (turn.load(std::memory_order_acquire) != k) {
          }
          turn.store(k + 1, std::memory_order_release);
        }
      }
    }
  }
  state.counters["per_round_trip"] = benchmark::Counter(
      static_cast<double>(kTrips),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(CacheLineRoundTrip)->UseRealTime();

// KickInChunks with the two chunks' threads swapped every pass: thread t kicks chunk
// (t + pass) mod 2, whose lines the other core wrote in the last pass.
void KickInSwappedChunks(benchmark::State& state) {
  Kick kick;
  std::int64_t pass = 0;
  for (auto _ : state) {
#pragma omp parallel num_threads(2)
    {
      const int chunk = (omp_get_thread_num() + static_cast<int>(pass % 2)) % 2;
      const IndexRange r = chunk_range(kParticles, chunk, 2);
      kick.pass(r.begin, r.end);
    }
    ++pass;
    benchmark::ClobberMemory();
  }
}
BENCHMARK(KickInSwappedChunks)->UseRealTime();

// Lines another core touched last, in bulk rather than one round trip at a time: in one job
// of the team, thread 1 writes every line of kLines lines, then (after the job's barrier)
// thread 0 reads them in order (argument 0) or in a shuffled order (1); the time of thread
// 0's reads per line. With the cores 400 ns apart (a round trip), a read of the line the
// other wrote costs a few nanoseconds in either order (bench/README.md, "Stop 56"): the cores
// fetch many lines at once.
constexpr std::size_t kLines = 500;
constexpr std::size_t kDoublesALine = 8;

std::vector<std::uint32_t> line_order(bool shuffled) {
  std::vector<std::uint32_t> order(kLines);
  std::iota(order.begin(), order.end(), 0u);
  if (shuffled) std::shuffle(order.begin(), order.end(), std::mt19937(1));
  return order;
}

// Per iteration, in one job of the team: thread 1's pass over the lines, the job's barrier,
// then thread 0's pass, timed; the time per line of thread 0's passes.
template <class OtherPass, class TimedPass>
void time_per_line(benchmark::State& state, OtherPass&& other, TimedPass&& timed) {
  for (auto _ : state) {
    double seconds = 0.0;
    auto job = [&](int thread, int) {
      if (thread == 1) other();
      team_barrier();
      if (thread != 0) return;
      const auto start = std::chrono::steady_clock::now();
      timed();
      seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    run_on_team(2, job);
    state.SetIterationTime(seconds);
  }
  state.counters["per_line"] = benchmark::Counter(
      static_cast<double>(kLines),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void ReadLinesTheOtherCoreWrote(benchmark::State& state) {
  const std::vector<std::uint32_t> order = line_order(state.range(0) != 0);
  std::vector<double> value(kLines * kDoublesALine, 1.0);
  double sum = 0.0;
  time_per_line(
      state,
      [&] {
        for (std::size_t k = 0; k < kLines; ++k) value[k * kDoublesALine] += 1.0;
      },
      [&] {
        for (const std::uint32_t k : order) sum += value[k * kDoublesALine];
      });
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(ReadLinesTheOtherCoreWrote)->Arg(0)->Arg(1)->UseManualTime();

// The other way: thread 1 reads every line, then thread 0 stores to each (its copies
// invalidated in the other core's cache); the time of thread 0's stores per line.
void StoreToLinesTheOtherCoreRead(benchmark::State& state) {
  std::vector<double> value(kLines * kDoublesALine, 1.0);
  double sum = 0.0;
  double stored = 0.0;
  time_per_line(
      state,
      [&] {
        for (std::size_t k = 0; k < kLines; ++k) sum += value[k * kDoublesALine];
      },
      [&] {
        stored += 1.0;
        for (std::size_t k = 0; k < kLines; ++k) value[k * kDoublesALine] = stored;
      });
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(StoreToLinesTheOtherCoreRead)->UseManualTime();

// A step's exchange between two threads as the pair loop of a 4000-particle box makes it (the
// rigid melt's chunks and LJ 4000's each touch about 3100 of the 4000: bench/README.md, "Stop
// 61"; here every particle), with no other work.
// In one job: each thread writes its half of kParticles positions (a solve's output: "write"),
// then, after a barrier, copies every position into a padded copy of its own and zeroes a
// padded force piece of its own over every particle ("gather"), adds a force to every third
// particle of its piece and, after a barrier, sums both pieces over its half ("sums"). Thread
// 0's times per step: every step each core writes lines the other read and reads lines the
// other wrote, which costs what the cores' distance makes it (CacheLineRoundTrip).
void HalvesExchanged(benchmark::State& state) {
  struct alignas(32) Padded {
    double x = 0.0, y = 0.0, z = 0.0, w = 0.0;
  };
  std::vector<Vec3> x(kParticles, Vec3{1.0, 2.0, 3.0});
  std::vector<Padded> copy[2], piece[2];
  for (int t = 0; t < 2; ++t) copy[t].resize(kParticles), piece[t].resize(kParticles);
  double write = 0.0, gather = 0.0, sums = 0.0, sum = 0.0;
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
  };
  for (auto _ : state) {
    auto job = [&](int thread, int) {
      const IndexRange half = chunk_range(kParticles, thread, 2);
      const auto t0 = Clock::now();
      for (std::size_t i = half.begin; i < half.end; ++i) x[i].x += 1e-9, x[i].y -= 1e-9;
      const auto t1 = Clock::now();
      team_barrier();
      const auto t2 = Clock::now();
      std::vector<Padded>& mine = copy[thread];
      std::vector<Padded>& f = piece[thread];
      for (std::size_t i = 0; i < kParticles; ++i) mine[i] = {x[i].x, x[i].y, x[i].z, 0.0};
      for (std::size_t i = 0; i < kParticles; ++i) f[i] = Padded{};
      const auto t3 = Clock::now();
      for (std::size_t i = 0; i < kParticles; i += 3) f[i].x += 1e-3 * mine[i].x;
      team_barrier();
      const auto t4 = Clock::now();
      const std::vector<Padded>& other = piece[1 - thread];
      double s = 0.0;
      for (std::size_t i = half.begin; i < half.end; ++i) s += f[i].x + other[i].x;
      const auto t5 = Clock::now();
      if (thread != 0) return;
      sum += s;
      write += seconds(t0, t1), gather += seconds(t2, t3), sums += seconds(t4, t5);
    };
    run_on_team(2, job);
  }
  benchmark::DoNotOptimize(sum);
  const auto steps = static_cast<double>(state.iterations());
  state.counters["write_us"] = 1e6 * write / steps;
  state.counters["gather_us"] = 1e6 * gather / steps;
  state.counters["sums_us"] = 1e6 * sums / steps;
}
BENCHMARK(HalvesExchanged)->UseRealTime();

// The same fixed work (state.range(0) microseconds on one thread) again and again: on one
// thread, how much a call's time changes from the call before; on two threads in one job of
// the team, each making the same work, how far apart their times are within a call and what
// the slower of the two costs over the mean. A loop whose chunks are fixed and must all end
// before the next pass (the pair forces' sums, in equal chunks for their bits) pays that on
// every call whatever its code: where a core's speed wanders from one tenth of a millisecond
// to the next (a virtual machine's vCPUs), it shows here. state.range(1): 0, arithmetic on
// data in L1; 1, a pair list's reads (a 4000-particle liquid's 150 000 listed partners, 0.6
// MB, each partner's position gathered from 128 KB, as the pair loop reads them).
class FixedWork {
 public:
  explicit FixedWork(bool gathers) : gathers_(gathers) {
    for (std::size_t i = 0; i < data_.size(); ++i) data_[i] = 1.0 + 1e-3 * static_cast<double>(i);
    if (!gathers_) return;
    std::mt19937 random(7);
    std::uniform_int_distribution<std::uint32_t> pick(0, kParticles - 1);
    partner_.resize(150000);
    for (std::uint32_t& j : partner_) j = pick(random);
    position_.assign(4 * kParticles, 1.0);
  }
  double run(std::size_t passes) const {
    double sum = 0.0;
    for (std::size_t p = 0; p < passes; ++p) {
      if (gathers_) {
        for (const std::uint32_t j : partner_) sum += position_[4 * j] * position_[4 * j + 1];
      } else {
        for (const double d : data_) sum += 1.0 / (d * d + sum * 1e-300);
      }
      benchmark::DoNotOptimize(sum);
    }
    return sum;
  }
  // Passes that take about `us` microseconds on this thread.
  std::size_t passes_for(double us) const {
    using Clock = std::chrono::steady_clock;
    const std::size_t trial = gathers_ ? 2 : 200;
    const auto t0 = Clock::now();
    for (int k = 0; k < 5; ++k) benchmark::DoNotOptimize(run(trial));
    const double per_pass = std::chrono::duration<double, std::micro>(Clock::now() - t0).count() /
                            (5.0 * static_cast<double>(trial));
    return std::max<std::size_t>(1, static_cast<std::size_t>(us / per_pass));
  }

 private:
  bool gathers_;
  std::array<double, 512> data_{};
  std::vector<std::uint32_t> partner_;
  std::vector<double> position_;
};

void FixedWorkJitterOneThread(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  const FixedWork work(state.range(1) != 0);
  const std::size_t passes = work.passes_for(static_cast<double>(state.range(0)));
  double total = 0.0, change = 0.0, last = 0.0;
  std::int64_t calls = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(work.run(passes));
    const double t = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    if (calls > 0) change += std::abs(t - last);
    last = t, total += t, ++calls;
  }
  const double mean = total / static_cast<double>(calls);
  state.counters["mean_us"] = mean;
  // A single call has no change to measure.
  state.counters["change_pct"] =
      calls > 1 ? 100.0 * change / static_cast<double>(calls - 1) / mean : 0.0;
}
BENCHMARK(FixedWorkJitterOneThread)->Args({300, 0})->Args({300, 1})->UseRealTime();

void FixedWorkJitterTwoThreads(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  // One copy a thread, made by its thread (its lines in its core's caches).
  std::array<std::unique_ptr<FixedWork>, 2> work;
  auto make = [&](int thread, int) {
    work[static_cast<std::size_t>(thread)] = std::make_unique<FixedWork>(state.range(1) != 0);
  };
  run_on_team(2, make);
  const std::size_t passes = work[0]->passes_for(static_cast<double>(state.range(0)));
  double total = 0.0, apart = 0.0, slower = 0.0;
  std::int64_t calls = 0;
  for (auto _ : state) {
    // Each thread's time on a line of its own, written once a call.
    std::array<OnItsOwnLine<double>, 2> t;
    auto job = [&](int thread, int) {
      const auto t0 = Clock::now();
      benchmark::DoNotOptimize(work[static_cast<std::size_t>(thread)]->run(passes));
      t[static_cast<std::size_t>(thread)].value =
          std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    };
    run_on_team(2, job);
    total += t[0].value + t[1].value;
    apart += std::abs(t[0].value - t[1].value);
    slower += std::max(t[0].value, t[1].value);
    ++calls;
  }
  const double mean = total / (2.0 * static_cast<double>(calls));
  state.counters["mean_us"] = mean;
  state.counters["apart_pct"] = 100.0 * apart / static_cast<double>(calls) / mean;
  state.counters["slower_over_mean_pct"] =
      100.0 * (slower / static_cast<double>(calls) / mean - 1.0);
}
BENCHMARK(FixedWorkJitterTwoThreads)->Args({300, 0})->Args({300, 1})->UseRealTime();

}  // namespace
}  // namespace deli

BENCHMARK_MAIN();
