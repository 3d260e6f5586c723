// Chunks at the threads' shares (core/chunk_balance.hpp): where they begin, how the shares
// move with the measured speeds, and that no number of a run depends on them. The expected
// numbers of a run are those of equal chunks (the chunks before the balance: stop 70's code,
// tools/same_results.sh), which moved chunks must give bit for bit: only loops whose numbers
// do not depend on their chunks follow the shares, and every sum over chunks keeps equal ones.
#include "core/chunk_balance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/integrator_factory.hpp"
#include "core/parallel.hpp"
#include "input/run_input.hpp"
#include "neighbor/neighbor_list.hpp"
#include "simulation/thermo.hpp"
#include "support/same_bits.hpp"
#include "support/short_runs.hpp"
#include "support/test_systems.hpp"
#include "support/thread_count.hpp"

namespace deli::balance_test {
namespace {

using testing::kThreaded;
using testing::same_bits;
using testing::ThreadCount;

// Holds `shares` for a scope, then equal chunks again.
class HeldShares {
 public:
  explicit HeldShares(const std::vector<double>& shares) { set_chunk_shares(shares); }
  ~HeldShares() { set_chunk_shares({}); }
  HeldShares(const HeldShares&) = delete;
  HeldShares& operator=(const HeldShares&) = delete;
};

TEST(ChunkBalance, ChunksBeginAtTheirThreadsSharesOfTheItems) {
  const HeldShares held({0.3, 0.7});
  EXPECT_EQ(chunk_range(1000, 0, 2).begin, 0u);
  EXPECT_EQ(chunk_range(1000, 0, 2).end, 300u);
  EXPECT_EQ(chunk_range(1000, 1, 2).begin, 300u);
  EXPECT_EQ(chunk_range(1000, 1, 2).end, 1000u);
  // Sums' chunks stay halves; loops of another chunk count, equal thirds.
  EXPECT_EQ(fixed_chunk_range(1000, 0, 2).end, 500u);
  EXPECT_EQ(chunk_range(999, 1, 3).begin, 333u);
  EXPECT_EQ(chunk_range(999, 2, 3).begin, 666u);
  // Ten items, item i holding i + 1 units of work (55 in all): 30 % of the work is 16.5
  // units, and the first item whose work begins at or past 16 is item 6 (from 21); half of
  // it, 27 units, item 7 (from 28).
  std::vector<std::size_t> offsets{0};
  for (std::size_t i = 0; i < 10; ++i) offsets.push_back(offsets.back() + i + 1);
  std::vector<std::size_t> starts;
  equal_work_starts(offsets.data(), 10, 2, starts);
  EXPECT_EQ(starts, (std::vector<std::size_t>{0, 6, 10}));
  equal_work_starts(offsets.data(), 10, 2, starts, true);
  EXPECT_EQ(starts, (std::vector<std::size_t>{0, 7, 10}));
}

// Equal shares are n c / chunks exactly (a third in floating point would round some of them).
TEST(ChunkBalance, EqualSharesAreTheEqualChunks) {
  for (const std::vector<double>& shares :
       {std::vector<double>{0.5, 0.5}, std::vector<double>(3, 1.0 / 3.0)}) {
    const HeldShares held(shares);
    const int chunks = static_cast<int>(shares.size());
    for (std::size_t n = 0; n < 200; ++n) {
      for (int c = 0; c < chunks; ++c) {
        EXPECT_EQ(chunk_range(n, c, chunks).begin, fixed_chunk_range(n, c, chunks).begin) << n;
        EXPECT_EQ(chunk_range(n, c, chunks).end, fixed_chunk_range(n, c, chunks).end) << n;
      }
    }
  }
}

// Thread 0 did half the items in 100 units of time, thread 1 the other half in 150: speeds
// 3 : 2, shares 0.6 and 0.4, halfway there from 0.5 is 0.55. From shares 0.7 and 0.3, a
// thread 1000 times slower than the other: halfway is 0.85 and 0.15, and the shares stop at
// 1.5 and 0.5 times an equal one. Nothing measured on a thread: no move.
TEST(ChunkBalance, SharesMoveHalfwayTowardsTheMeasuredSpeeds) {
  const std::vector<double> moved = moved_shares({0.5, 0.5}, {100.0, 150.0});
  EXPECT_NEAR(moved[0], 0.55, 1e-15);
  EXPECT_NEAR(moved[1], 0.45, 1e-15);
  const std::vector<double> stopped = moved_shares({0.7, 0.3}, {1.0, 1000.0});
  EXPECT_NEAR(stopped[0], 0.75, 1e-15);
  EXPECT_NEAR(stopped[1], 0.25, 1e-15);
  EXPECT_EQ(moved_shares({0.4, 0.6}, {0.0, 100.0}), (std::vector<double>{0.4, 0.6}));
}

// The run loop's calls: the first holds equal shares; then a move once 4 ms were measured,
// away from the busier (slower) thread; with the balance off, equal chunks and no move.
TEST(ChunkBalance, RebalanceMovesAwayFromTheSlowerThreadOnceEnoughIsMeasured) {
  set_chunk_shares({});
  rebalance_chunks(2);
  EXPECT_EQ(chunk_shares(), (std::vector<double>{0.5, 0.5}));
  add_balanced_busy(0, 1'200'000);
  add_balanced_busy(1, 800'000);
  rebalance_chunks(2);  // 2 ms measured: not yet
  EXPECT_EQ(chunk_shares(), (std::vector<double>{0.5, 0.5}));
  add_balanced_busy(0, 1'800'000);
  add_balanced_busy(1, 1'200'000);
  const long long moves = chunk_balance_moves();
  rebalance_chunks(2);  // 5 ms: thread 0 took 1.5 times thread 1's time for as many items
  EXPECT_EQ(chunk_balance_moves(), moves + 1);
  ASSERT_EQ(chunk_shares().size(), 2u);
  EXPECT_NEAR(chunk_shares()[0], 0.5 + 0.5 * (0.4 - 0.5), 1e-15);
  set_chunk_balance(false);
  EXPECT_TRUE(chunk_shares().empty());
  EXPECT_EQ(chunk_range(1000, 1, 2).begin, 500u);
  add_balanced_busy(1, 9'000'000);
  rebalance_chunks(2);
  EXPECT_TRUE(chunk_shares().empty());
  set_chunk_balance(true);
  set_chunk_shares({});
}

// What a run's numbers are after some steps: the trajectory, the sums a thermo row makes and
// the integrator's own figures.
struct RunNumbers {
  std::vector<Vec3> position, velocity;
  double kinetic = 0.0, potential = 0.0, virial = 0.0, constraint_virial = 0.0;
  Vec3 momentum;
  std::optional<double> bath, shadow;
  std::vector<std::pair<std::string, double>> statistics;
};

RunNumbers run_with_shares(const RunInput& input, const std::vector<double>& shares, int steps) {
  const ThreadCount two(2);
  const HeldShares held(shares);
  System system = input.system;
  const std::unique_ptr<Integrator> integrator = make_unsorted_integrator(input);
  integrator->setup(system);
  for (int n = 0; n < steps; ++n) integrator->step(system, true);
  RunNumbers out;
  out.position = system.particles.position;
  out.velocity = system.particles.velocity;
  out.kinetic = kinetic_energy(system.particles);
  out.momentum = total_momentum(system.particles);
  out.potential = integrator->forces().last().potential;
  out.virial = integrator->forces().last().virial.trace();
  out.constraint_virial = integrator->take_constraint_virial();
  out.bath = integrator->bath_energy();
  out.shadow = integrator->shadow_energy(system);
  out.statistics = integrator->take_statistics();
  return out;
}

void expect_same_numbers(const RunNumbers& a, const RunNumbers& b, const std::string& what) {
  EXPECT_TRUE(same_bits(a.position, b.position)) << what;
  EXPECT_TRUE(same_bits(a.velocity, b.velocity)) << what;
  EXPECT_EQ(a.kinetic, b.kinetic) << what;
  EXPECT_EQ(a.momentum.x, b.momentum.x) << what;
  EXPECT_EQ(a.momentum.y, b.momentum.y) << what;
  EXPECT_EQ(a.momentum.z, b.momentum.z) << what;
  EXPECT_EQ(a.potential, b.potential) << what;
  EXPECT_EQ(a.virial, b.virial) << what;
  EXPECT_EQ(a.constraint_virial, b.constraint_virial) << what;
  EXPECT_EQ(a.bath, b.bath) << what;
  EXPECT_EQ(a.shadow, b.shadow) << what;
  EXPECT_EQ(a.statistics, b.statistics) << what;
}

std::string thermostat(const std::string& type) {
  return "[thermostat]\ntype = \"" + type + "\"\ntemperature = 1.2\ndamping = 0.1\nseed = 17\n";
}

// Each case's loops past the length from which two threads split them (ThreadCount: 1024
// items): the paths of every kind of loop that follows the shares or must not.
struct BalancedCase {
  std::string name;
  RunInput (*make)();
};

// 1372 hard spheres (GVI, reflections, the guard) under CSVR, whose scale factor is a sum
// over the particles: a kinetic energy grouped by the shares would move the trajectory.
RunInput hard_spheres_csvr() {
  return testing::hard_sphere_fluid(7, thermostat("csvr"));
}

// The 4000-atom harmonic chain melt (LJ in cell order through the touched blocks' vector
// loops, bonds through per-chunk buffers), velocity Verlet.
RunInput harmonic_melt() {
  RunInput input = load_run_input(DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000_harmonic.toml");
  testing::jiggle(input.system.particles, 0.05, 11);
  return input;
}

// 1200 beads of rod chains with LJ between them (GVI: the rods' cluster loops, pair forces
// inside the step).
RunInput lj_rod_chains() {
  return testing::thirty_bead_lj_rod_chains();
}

// 1500 beads with bonds, angles and dihedrals (per-chunk buffers of every bonded term) under
// Langevin (draws by particle).
RunInput dihedral_chains_langevin() {
  return testing::dihedral_chains(150, 10, thermostat("langevin"));
}

class RunsWhereverTheChunksBegin : public ::testing::TestWithParam<BalancedCase> {};

TEST_P(RunsWhereverTheChunksBegin, GiveTheEqualChunksNumbersBitForBit) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const RunInput input = GetParam().make();
  const int steps = testing::steps_or_prefix(10, 3);
  const RunNumbers equal = run_with_shares(input, {0.5, 0.5}, steps);
  EXPECT_GT(equal.kinetic, 0.0);
  for (const std::vector<double>& shares :
       {std::vector<double>{0.31, 0.69}, std::vector<double>{0.68, 0.32}}) {
    expect_same_numbers(equal, run_with_shares(input, shares, steps),
                        GetParam().name + " at " + std::to_string(shares[0]));
  }
}

// v^T H v of the pair forces (the shadow energy's curvature, and the impact-time step's energy
// restoration), a sum of some 10^5 pair terms over chunks of particles: the same bits at any
// shares. (In a run's shadow energy its last bits are scaled by h^2 / 12 below the energy's.)
TEST(ChunkBalance, PairCurvatureIsTheSameSumWhereverTheChunksBegin) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const RunInput input = harmonic_melt();
  NeighborList list(input.force_field->neighbor_cutoff(), 0.3);
  list.build(input.system.particles.position, input.system.box);
  std::vector<Vec3> velocity(input.system.particles.size());
  for (std::size_t i = 0; i < velocity.size(); ++i) {
    velocity[i] = Vec3{std::sin(1.0 * i), std::cos(2.0 * i), std::sin(3.0 * i + 1.0)};
  }
  auto curvature = [&](const std::vector<double>& shares) {
    const ThreadCount two(2);
    const HeldShares held(shares);
    double sum = 0.0;
    EXPECT_TRUE(input.force_field->pair_curvature(input.system, list, velocity, sum));
    return sum;
  };
  const double equal = curvature({0.5, 0.5});
  EXPECT_NE(equal, 0.0);
  EXPECT_EQ(curvature({0.31, 0.69}), equal);
  EXPECT_EQ(curvature({0.68, 0.32}), equal);
}

INSTANTIATE_TEST_SUITE_P(
    Systems, RunsWhereverTheChunksBegin,
    ::testing::Values(BalancedCase{"hard_spheres_csvr", hard_spheres_csvr},
                      BalancedCase{"harmonic_melt", harmonic_melt},
                      BalancedCase{"lj_rod_chains", lj_rod_chains},
                      BalancedCase{"dihedral_chains_langevin", dihedral_chains_langevin}),
    [](const ::testing::TestParamInfo<BalancedCase>& info) { return info.param.name; });

}  // namespace
}  // namespace deli::balance_test
