// What deli's threading costs per call on this machine (Google Benchmark; not a test), with
// 2 threads unless OMP_NUM_THREADS says otherwise: an empty chunked loop (one parallel
// region: for_each_chunk), a barrier inside one region, and a cheap pass over 4000
// particles (a kick: p += f h/2, as GVI's and velocity Verlet's per-particle passes) on the
// calling thread alone and split into chunks. A pass of a few microseconds gains from a
// second thread only where the split saves more than a region costs.
//   cmake --build build --target deli-parallel-overhead
//   OMP_NUM_THREADS=2 build/bench/parallel_overhead/deli-parallel-overhead
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <vector>

#include "core/parallel.hpp"
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

// Barriers inside one region, as a step kept in one region would meet between its phases.
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

}  // namespace
}  // namespace deli

BENCHMARK_MAIN();
