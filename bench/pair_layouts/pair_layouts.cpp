// The LJ pair loop on deli's half list (LennardJones::vector_loop) against the same pairs in
// two cluster layouts (cluster_layouts.hpp: quads, 4x1, and cluster pairs, 4x4, GROMACS'
// layout), and what making each layout from the list costs (once per list build). A 32000-atom
// jittered fcc lattice at the LJ benchmark's density (0.8442), cutoff 2.5, skin 0.3: in
// lattice order (each atom's neighbours near it in index) and shuffled, then read in the
// list's cell order ([neighbor] cell_order). Before timing, each cluster kernel's forces are
// checked against its scalar form (the same bits) and against the list loop's (round-off).
// Google Benchmark; not a test. bench/README.md, "Stop 45", has the figures.
//   cmake --build build --target deli-pair-layouts
//   taskset -c 0 build/bench/pair_layouts/deli-pair-layouts --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "cluster_layouts.hpp"

namespace deli::bench {
namespace {

struct Liquid {
  std::size_t n = 0;
  NeighborList list{2.5, 0.3};
  NeighborList::PartnerRanges ranges;
  std::vector<PaddedVec3> x;  // by item, padded to a multiple of four
  LennardJones::Params p = LennardJones::make(1.0, 1.0, 2.5);
  std::size_t pairs = 0;

  explicit Liquid(bool shuffled) {
    const int cells = 20;
    const double a = std::cbrt(4.0 / 0.8442);
    const Box box({0, 0, 0}, {cells * a, cells * a, cells * a}, {true, true, true});
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> jitter(-0.15, 0.15);
    const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
    std::vector<Vec3> position;
    for (int i = 0; i < cells; ++i)
      for (int j = 0; j < cells; ++j)
        for (int k = 0; k < cells; ++k)
          for (const auto& b : basis) {
            position.push_back({(i + b[0]) * a + jitter(rng), (j + b[1]) * a + jitter(rng),
                                (k + b[2]) * a + jitter(rng)});
          }
    if (shuffled) std::shuffle(position.begin(), position.end(), rng);
    list.set_cell_order(shuffled);
    list.build(position, box);
    n = position.size();
    ranges = shuffled ? list.cell_ordered().ranges() : list.partner_ranges();
    x.assign((n + 3) / 4 * 4, PaddedVec3{});
    for (std::size_t s = 0; s < n; ++s) {
      const Vec3& v =
          position[shuffled ? static_cast<std::size_t>(list.cell_ordered().particle[s]) : s];
      x[s] = {v.x, v.y, v.z, 0.0};
    }
    for (std::size_t i = 0; i < n; ++i) pairs += ranges.end[i] - ranges.begin[i];
  }

  std::vector<PaddedVec3> list_forces() const {
    std::vector<PaddedVec3> f(x.size());
    SymTensor w;
    LennardJones::vector_loop(p, chunk(f), false, w);
    return f;
  }
  VectorPairChunk chunk(std::vector<PaddedVec3>& f) const {
    return {x.data(),
            f.data(),
            ranges.neighbors,
            ranges.image_codes,
            ranges.begin,
            list.image_shifts().data(),
            0,
            static_cast<std::int32_t>(n),
            ranges.end};
  }
};

const Liquid& liquid(bool shuffled) {
  static const Liquid lattice(false), mixed(true);
  return shuffled ? mixed : lattice;
}

void report(benchmark::State& state, const Liquid& l) {
  state.counters["per_atom"] =
      benchmark::Counter(static_cast<double>(l.n), benchmark::Counter::kIsIterationInvariantRate |
                                                       benchmark::Counter::kInvert);
}

void ListLoop(benchmark::State& state) {
  const Liquid& l = liquid(state.range(0) != 0);
  std::vector<PaddedVec3> f(l.x.size());
  SymTensor w;
  for (auto _ : state) {
    std::fill(f.begin(), f.end(), PaddedVec3{});
    LennardJones::vector_loop(l.p, l.chunk(f), false, w);
    benchmark::ClobberMemory();
  }
  state.counters["pairs_per_atom"] = static_cast<double>(l.pairs) / static_cast<double>(l.n);
  report(state, l);
}

using Make = void (*)(const NeighborList::PartnerRanges&, std::size_t, ClusterEntries&,
                      std::vector<std::int32_t>&, std::vector<std::int32_t>&);
using Kernel = void (*)(const LennardJones::Params&, const ClusterChunk&);

// The layout's kernel, checked first against its scalar form and the list loop.
[[maybe_unused]] void Layout(benchmark::State& state, Make make, Kernel kernel, Kernel scalar) {
  const Liquid& l = liquid(state.range(0) != 0);
  ClusterEntries entries;
  std::vector<std::int32_t> stamp, entry_of;
  make(l.ranges, l.n, entries, stamp, entry_of);
  const ClusterChunk base{l.x.data(), nullptr,      &entries, l.list.image_shifts().data(),
                          0,          (l.n + 3) / 4};
  std::vector<PaddedVec3> f(l.x.size()), g(l.x.size());
  ClusterChunk c = base, s = base;
  c.f = f.data(), s.f = g.data();
  kernel(l.p, c);
  scalar(l.p, s);
  const std::vector<PaddedVec3> reference = l.list_forces();
  double largest = 0.0, off = 0.0;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < l.n; ++i) {
    differ += (f[i].x != g[i].x) + (f[i].y != g[i].y) + (f[i].z != g[i].z);
    largest = std::max(
        {largest, std::abs(reference[i].x), std::abs(reference[i].y), std::abs(reference[i].z)});
    off = std::max({off, std::abs(f[i].x - reference[i].x), std::abs(f[i].y - reference[i].y),
                    std::abs(f[i].z - reference[i].z)});
  }
  if (differ != 0 || off > 1e-12 * largest) {
    state.SkipWithError(("forces: " + std::to_string(differ) +
                         " components differ from the scalar form's, " +
                         std::to_string(off / largest) + " of the largest from the list loop's")
                            .c_str());
    return;
  }
  for (auto _ : state) {
    std::fill(f.begin(), f.end(), PaddedVec3{});
    kernel(l.p, c);
    benchmark::ClobberMemory();
  }
  state.counters["entries_per_atom"] =
      static_cast<double>(entries.partner.size()) / static_cast<double>(l.n);
  if (make == &make_cluster_pairs) {
    std::size_t rows = 0;  // a cluster pair's rows with a pair (the kernel's vectors)
    for (const std::uint16_t b : entries.bits) {
      for (int a = 0; a < 4; ++a) rows += (b >> (4 * a) & 15u) != 0;
    }
    state.counters["rows_per_atom"] = static_cast<double>(rows) / static_cast<double>(l.n);
  }
  report(state, l);
}

void Making(benchmark::State& state, Make make) {
  const Liquid& l = liquid(state.range(0) != 0);
  ClusterEntries entries;
  std::vector<std::int32_t> stamp, entry_of;
  for (auto _ : state) {
    make(l.ranges, l.n, entries, stamp, entry_of);
    benchmark::DoNotOptimize(entries.partner.data());
  }
  report(state, l);
}

#ifdef __AVX2__
void Quads(benchmark::State& state) {
  Layout(state, &make_quads, &quads_avx2, &quads_scalar);
}
void ClusterPairs(benchmark::State& state) {
  Layout(state, &make_cluster_pairs, &cluster_pairs_avx2, &cluster_pairs_scalar);
}
#else
void Quads(benchmark::State& state) {
  state.SkipWithError("the cluster kernels need AVX2 (a DELI_NATIVE build on an AVX2 CPU)");
}
void ClusterPairs(benchmark::State& state) {
  Quads(state);
}
#endif
void MakeQuads(benchmark::State& state) {
  Making(state, &make_quads);
}
void MakeClusterPairs(benchmark::State& state) {
  Making(state, &make_cluster_pairs);
}

// Argument: 0 lattice order, 1 shuffled and read in cell order.
BENCHMARK(ListLoop)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(Quads)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(ClusterPairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(MakeQuads)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(MakeClusterPairs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace deli::bench

BENCHMARK_MAIN();
