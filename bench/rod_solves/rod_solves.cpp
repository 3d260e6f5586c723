// The rigid melt's rod solves alone (Google Benchmark; not a test): 100 chains of 40 beads
// (random walks of unit rods, unit masses, in the melt's periodic box), solved in lockstep
// groups of RodChainLanes::width as ConstrainedIntegrator::solve_positions and
// project_momenta do. Times per chain: the position solve from the start positions (their
// directions remembered by the projection there, as at every step of a run) and the
// momentum projection. bench/README.md, "Rods' share of the rigid melt (round 12)".
#include <benchmark/benchmark.h>

#include <array>
#include <memory>
#include <random>
#include <vector>

#include "solvers/rod_chain.hpp"

namespace deli {
namespace {

constexpr std::size_t chain_count = 100, beads = 40, width = RodChainLanes::width;

struct Melt {
  Box box{{0, 0, 0}, {16.8, 16.8, 16.8}, {true, true, true}};
  std::vector<Vec3> q, delta, p, impulse;
  std::vector<std::unique_ptr<RodChain>> chains;
  RodChainLanes lanes;

  Melt() {
    std::mt19937_64 rng(12);
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> place(0.0, 16.8);
    for (std::size_t c = 0; c < chain_count; ++c) {
      LocalCluster cluster;
      Vec3 x{place(rng), place(rng), place(rng)};
      for (std::size_t k = 0; k < beads; ++k) {
        if (k > 0) {
          const Vec3 step{normal(rng), normal(rng), normal(rng)};
          x += step * (1.0 / norm(step));
        }
        Vec3 wrapped = x;
        std::array<int, 3> image{};
        box.wrap(wrapped, image);
        q.push_back(wrapped);
        // About the melt's free step: h |v| with |v| ~ 1.7 at T = 1, h = 0.005.
        delta.push_back(Vec3{normal(rng), normal(rng), normal(rng)} * 0.005);
        p.push_back(Vec3{normal(rng), normal(rng), normal(rng)});
        cluster.particles.push_back(static_cast<std::int32_t>(q.size() - 1));
        cluster.inverse_mass.push_back(1.0);
      }
      for (std::size_t k = 0; k + 1 < beads; ++k) {
        Constraint rod;
        rod.kind = ConstraintKind::rod;
        rod.i = static_cast<std::int32_t>(k);
        rod.j = static_cast<std::int32_t>(k + 1);
        rod.length = 1.0;
        cluster.rows.push_back(rod);
        cluster.global_rows.push_back(static_cast<std::int32_t>(k));
      }
      chains.push_back(RodChain::make(cluster));
    }
    impulse.resize(q.size());
  }

  // Every group of up to `width` consecutive chains, as by_chain_runs forms them.
  template <class Each>
  void groups(const Each& each) {
    for (std::size_t first = 0; first < chain_count; first += width) {
      const RodChain* group[width];
      const std::size_t count = std::min(width, chain_count - first);
      for (std::size_t l = 0; l < count; ++l) group[l] = chains[first + l].get();
      each(group, count);
    }
  }
  void project(const std::vector<Vec3>& at, std::vector<Vec3>& momenta) {
    groups([&](const RodChain** group, std::size_t count) {
      bool solved[width];
      RodChain::project_momenta_lanes(group, count, at.data(), momenta.data(), box, lanes, solved);
    });
  }
  // Solved chains (a lane left to the chain kernel alone counts as unsolved here).
  std::size_t solve() {
    std::size_t done = 0;
    groups([&](const RodChain** group, std::size_t count) {
      double virial[width];
      SolverStatus status[width];
      bool solved[width];
      RodChain::solve_positions_lanes(group, count, q.data(), delta.data(), 0.005, box, 1e-12, 50,
                                      lanes, impulse.data(), virial, status, solved);
      for (std::size_t l = 0; l < count; ++l) done += solved[l];
    });
    return done;
  }
};

void PositionSolve(benchmark::State& state) {
  Melt melt;
  melt.project(melt.q, melt.p);  // the start directions remembered, as after a step
  for (auto _ : state) benchmark::DoNotOptimize(melt.solve());
  state.counters["ns_per_chain"] = benchmark::Counter(
      static_cast<double>(chain_count),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["unsolved"] = static_cast<double>(chain_count - melt.solve());
}
BENCHMARK(PositionSolve);

void MomentumProjection(benchmark::State& state) {
  Melt melt;
  for (auto _ : state) {
    melt.project(melt.q, melt.p);
    benchmark::DoNotOptimize(melt.p.data());
  }
  state.counters["ns_per_chain"] = benchmark::Counter(
      static_cast<double>(chain_count),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(MomentumProjection);

}  // namespace
}  // namespace deli

BENCHMARK_MAIN();
