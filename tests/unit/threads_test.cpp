// Threads (OpenMP): the same input on as many threads gives the same numbers bit for bit;
// across thread counts only the order of additions changes (forces, energies and virial
// agree to round-off), and the neighbour list is the same list. The expected values are
// the one-thread evaluation of the same code (the serial loop, bit for bit: same_results.sh
// against main).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "constraints/clusters.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "neighbor/neighbor_list.hpp"
#include "pair/lennard_jones.hpp"
#include "support/same_bits.hpp"
#include "support/scratch_files.hpp"
#include "support/short_runs.hpp"
#include "support/statistic.hpp"
#include "support/test_systems.hpp"
#include "support/thread_count.hpp"

namespace deli {
namespace {

using testing::kThreaded;
using testing::same_bits;
using testing::ThreadCount;

// 100 harmonic chains of 40 beads: 4000 particles and 3900 bonds, both past the length
// from which loops are cut into chunks, with shifted LJ and bonded exclusions.
RunInput chain_melt() {
  RunInput input = load_run_input(DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000_harmonic.toml");
  testing::jiggle(input.system.particles, 0.05, 11);
  return input;
}

// 150 chains of 10 beads with harmonic bonds, angles and dihedrals (the cross-check
// input tests/crosscheck/inputs/chains_dihedrals.toml, larger): 1050 dihedrals, past the
// length from which loops are cut into chunks.
RunInput dihedral_chains() {
  RunInput input = testing::dihedral_chains(150, 10);
  testing::jiggle(input.system.particles, 0.05, 12);
  return input;
}

// Evaluates `input` on 1 thread, then twice on 2: the two 2-thread evaluations are the
// same bits; 1 and 2 threads agree to round-off. Each force is a sum of some 40 terms of
// size up to ~100 (bonds), so a regrouping moves it by a few ulps of that size.
void expect_repeat_and_round_off(const RunInput& input) {
  testing::Evaluated one, two, again;
  {
    const ThreadCount threads(1);
    one = testing::evaluate(input);
  }
  {
    const ThreadCount threads(2);
    two = testing::evaluate(input);
    again = testing::evaluate(input);
  }
  EXPECT_TRUE(same_bits(two.force, again.force));
  EXPECT_EQ(two.evaluation.potential, again.evaluation.potential);
  EXPECT_EQ(two.evaluation.virial.trace(), again.evaluation.virial.trace());

  double largest = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < one.force.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      largest = std::max(largest, std::abs(one.force[i][a]));
      worst = std::max(worst, std::abs(one.force[i][a] - two.force[i][a]));
    }
  }
  EXPECT_LT(worst, 1e-12 * largest);
  EXPECT_NEAR(two.evaluation.potential, one.evaluation.potential,
              1e-13 * std::abs(one.evaluation.potential));
  EXPECT_NEAR(two.evaluation.virial.trace(), one.evaluation.virial.trace(),
              1e-13 * std::abs(one.evaluation.virial.trace()));
}

TEST(Threads, TwoThreadsRepeatBitForBitAndAgreeWithOneToRoundOff) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  expect_repeat_and_round_off(chain_melt());
}

TEST(Threads, DihedralsOnTwoThreadsRepeatBitForBitAndAgreeWithOneToRoundOff) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const RunInput input = dihedral_chains();
  ASSERT_GE(input.system.topology.dihedrals.size(), kParallelMinimum);
  expect_repeat_and_round_off(input);
  // The dihedral term alone too: its forces are small beside the pairs' and bonds'.
  const ForceTerm* dihedral = nullptr;
  for (const auto& term : input.force_field->terms()) {
    if (term->name() == "dihedral") dihedral = term.get();
  }
  ASSERT_NE(dihedral, nullptr);
  const NeighborList unused(2.5, 0.3);
  auto dihedral_forces = [&](int threads, double& energy, SymTensor& virial) {
    const ThreadCount count(threads);
    std::vector<Vec3> force(input.system.particles.size());
    energy = dihedral->compute(input.system, unused, force, virial, true);
    return force;
  };
  double e1, e2, e2_again;
  SymTensor w1, w2, w2_again;
  const std::vector<Vec3> f1 = dihedral_forces(1, e1, w1), f2 = dihedral_forces(2, e2, w2),
                          f2_again = dihedral_forces(2, e2_again, w2_again);
  EXPECT_TRUE(same_bits(f2, f2_again));
  EXPECT_EQ(e2, e2_again);
  EXPECT_EQ(w2.trace(), w2_again.trace());
  double largest = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < f1.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      largest = std::max(largest, std::abs(f1[i][a]));
      worst = std::max(worst, std::abs(f1[i][a] - f2[i][a]));
    }
  }
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(worst, 1e-13 * largest);
  EXPECT_NEAR(e2, e1, 1e-13 * std::abs(e1));
  // The virial's trace vanishes (a torsion's energy does not change when its four atoms'
  // separations scale together): compare the components, to round-off of the largest.
  const double w1s[6] = {w1.xx, w1.yy, w1.zz, w1.xy, w1.xz, w1.yz};
  const double w2s[6] = {w2.xx, w2.yy, w2.zz, w2.xy, w2.xz, w2.yz};
  double w_largest = 0.0;
  for (double v : w1s) w_largest = std::max(w_largest, std::abs(v));
  EXPECT_GT(w_largest, 1.0);
  for (int c = 0; c < 6; ++c) EXPECT_NEAR(w2s[c], w1s[c], 1e-12 * w_largest) << "component " << c;
}

// equal_work_starts (the pair loops' and the short list's scan's chunks): by its definition each
// chunk c starts at the first item whose work begins at or past c k-ths of the whole, so the
// chunks cut [0, n) in order and each holds its share of the work to within one item's.
TEST(Threads, EqualWorkStartsCutTheItemsIntoSharesWithinOneItem) {
  std::mt19937_64 random(11);
  // Uneven items, heavier towards the start (as hs_4000's first chunk held more pairs).
  std::uniform_int_distribution<std::size_t> work(0, 40);
  const std::size_t n = 4000;
  std::vector<std::size_t> offsets(n + 1, 0);
  std::size_t largest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t w = work(random) + (i < n / 8 ? 30 : 0);
    largest = std::max(largest, w);
    offsets[i + 1] = offsets[i] + w;
  }
  for (const int chunks : {1, 2, 3, 8}) {
    std::vector<std::size_t> starts;
    equal_work_starts(offsets.data(), n, chunks, starts);
    ASSERT_EQ(starts.size(), static_cast<std::size_t>(chunks) + 1);
    EXPECT_EQ(starts.front(), 0u);
    EXPECT_EQ(starts.back(), n);
    const double share = static_cast<double>(offsets[n]) / chunks;
    for (int c = 0; c < chunks; ++c) {
      EXPECT_LE(starts[c], starts[c + 1]) << chunks << " chunks, chunk " << c;
      const double held = static_cast<double>(offsets[starts[c + 1]] - offsets[starts[c]]);
      EXPECT_LE(std::abs(held - share), static_cast<double>(largest))
          << chunks << " chunks, chunk " << c;
    }
  }
}

TEST(Threads, NeighbourListIsTheSameListOnAnyThreadCount) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  // Positions inside the box, as a run wraps them: the list then has image codes too.
  const RunInput input =
      load_run_input(DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000_harmonic.toml");
  NeighborList serial(2.5, 0.3), threaded(2.5, 0.3);
  {
    const ThreadCount threads(1);
    serial.build(input.system.particles.position, input.system.box);
  }
  {
    const ThreadCount threads(2);
    threaded.build(input.system.particles.position, input.system.box);
  }
  EXPECT_EQ(serial.neighbors(), threaded.neighbors());
  EXPECT_EQ(serial.offsets(), threaded.offsets());
  EXPECT_EQ(serial.image_codes(), threaded.image_codes());
  EXPECT_FALSE(serial.image_codes().empty());
}

// A list object rebuilt keeps its scratch arrays between builds: its list after other
// positions, and after more and then fewer particles, is the list a fresh object builds.
TEST(Threads, ARebuiltNeighbourListIsAFreshlyBuiltOne) {
  const RunInput input =
      load_run_input(DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000_harmonic.toml");
  std::vector<Vec3> moved = input.system.particles.position;
  std::vector<Vec3> fewer(moved.begin(), moved.begin() + 1500);
  Particles jiggled = input.system.particles;
  testing::jiggle(jiggled, 0.1, 13);
  for (const int threads : {1, 2}) {
    if (threads == 2 && !kThreaded) continue;
    const ThreadCount count(threads);
    NeighborList reused(2.5, 0.3);
    for (const std::vector<Vec3>* positions : {&moved, &jiggled.position, &fewer}) {
      reused.build(*positions, input.system.box);
      NeighborList fresh(2.5, 0.3);
      fresh.build(*positions, input.system.box);
      EXPECT_EQ(reused.neighbors(), fresh.neighbors()) << positions->size() << " particles";
      EXPECT_EQ(reused.offsets(), fresh.offsets());
      EXPECT_EQ(reused.image_codes(), fresh.image_codes());
    }
  }
}

// v^T H v of the pair forces: on one thread the sum over pair_hessians' blocks in their
// order, summed here (to round-off only: the pair styles' files are compiled for the native
// instruction set and this file not, and Eigen's 3x3 products round with the packet
// width); on two threads the same bits on every call, and the one-thread sum to round-off
// (a regrouped sum of about 10^5 terms).
TEST(Threads, PairCurvatureOnTwoThreadsRepeatsAndAgreesWithOneToRoundOff) {
  const RunInput input = chain_melt();
  NeighborList list(input.force_field->neighbor_cutoff(), 0.3);
  list.build(input.system.particles.position, input.system.box);
  std::vector<Vec3> velocity(input.system.particles.size());
  std::mt19937_64 rng(17);
  std::normal_distribution<double> gauss;
  for (Vec3& v : velocity) v = Vec3{gauss(rng), gauss(rng), gauss(rng)};

  std::vector<PairHessian> blocks;
  ASSERT_TRUE(input.force_field->pair_hessians(input.system, list, {}, blocks));
  double from_blocks = 0.0;
  for (const PairHessian& b : blocks) {
    from_blocks += block_curvature(b.block, velocity[b.a], velocity[b.b]);
  }
  auto curvature = [&] {
    double sum = 0.0;
    EXPECT_TRUE(input.force_field->pair_curvature(input.system, list, velocity, sum));
    return sum;
  };
  double one = 0.0;
  {
    const ThreadCount threads(1);
    one = curvature();
  }
  double magnitude = 0.0;
  for (const PairHessian& b : blocks) {
    magnitude += std::abs(block_curvature(b.block, velocity[b.a], velocity[b.b]));
  }
  EXPECT_NEAR(one, from_blocks, 1e-13 * magnitude);
  if (!kThreaded) return;
  const ThreadCount threads(2);
  const double two = curvature();
  EXPECT_EQ(curvature(), two);
  EXPECT_NEAR(two, one, 1e-13 * magnitude);
}

// The pair Hessian blocks of the pairs touching masked particles (shadow-H reflections' blocks),
// made in chunks of particles on two threads: the one-thread blocks, bit for bit and in the
// same order. On one thread they are, bit for bit and in order, the blocks of the listed pairs
// within the cutoff that touch a masked particle, each made here pair by pair from the list
// by particle by pair_hessian_block (the special bonds 0 1 1 leave no scaled pair outside the
// list): the pair style's loop runs in vectors, with the same operations on each pair.
// With cell order on, the list by particle is read in order and split in chunks of equal
// numbers of pairs; without, in equal numbers of particles.
class MaskedPairHessians : public ::testing::TestWithParam<bool> {};

TEST_P(MaskedPairHessians, OnTwoThreadsAreTheOneThreadBlocks) {
  const RunInput input = chain_melt();
  NeighborList list(input.force_field->neighbor_cutoff(), 0.3);
  list.set_cell_order(GetParam());
  list.build(input.system.particles.position, input.system.box);
  // With image codes the style takes each separation as x_i - x_j less the listed pair's
  // shift; here it is made by minimum_image(): the same bits.
  ASSERT_TRUE(list.coded());
  const std::size_t n = input.system.particles.size();
  std::vector<char> mask(n, 0);
  for (std::size_t i = 0; i < n; i += 37) mask[i] = 1;
  for (std::size_t i = 1000; i < 1040; ++i) mask[i] = 1;  // a whole chain, as a cluster
  // The pair style's blocks alone (the bonds add theirs in the force field's).
  const ForceTerm& pair = *input.force_field->terms().front();
  ASSERT_EQ(pair.name(), "pair");
  auto blocks_on = [&](int threads) {
    const ThreadCount count(threads);
    std::vector<PairHessian> blocks;
    EXPECT_TRUE(pair.pair_hessians(input.system, list, mask, blocks));
    return blocks;
  };
  const std::vector<PairHessian> one = blocks_on(1);
  std::vector<PairHessian> expected;
  const double cutoff = input.force_field->neighbor_cutoff();
  const LennardJones::Params lj = LennardJones::make(1.0, 1.0, cutoff);  // the melt's pair style
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = list.offsets()[i]; k < list.offsets()[i + 1]; ++k) {
      const auto j = static_cast<std::size_t>(list.neighbors()[k]);
      const Vec3 d = input.system.box.minimum_image(input.system.particles.position[i] -
                                                    input.system.particles.position[j]);
      const double r2 = norm2(d);
      if (!(mask[i] || mask[j]) || r2 >= cutoff * cutoff) continue;
      double f_over_r, energy;
      LennardJones::evaluate(lj, r2, f_over_r, energy);
      expected.push_back(
          {static_cast<std::int32_t>(i), static_cast<std::int32_t>(j),
           pair_hessian_block(d, r2, f_over_r, LennardJones::second_derivative(lj, r2))});
    }
  }
  EXPECT_GT(expected.size(), 1000u);
  ASSERT_EQ(one.size(), expected.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_EQ(one[k].a, expected[k].a) << k;
    ASSERT_EQ(one[k].b, expected[k].b) << k;
    for (int e = 0; e < 9; ++e) ASSERT_EQ(one[k].block(e), expected[k].block(e)) << k << " " << e;
  }
  if (!kThreaded) return;
  const std::vector<PairHessian> two = blocks_on(2);
  ASSERT_EQ(two.size(), one.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_EQ(two[k].a, one[k].a) << k;
    ASSERT_EQ(two[k].b, one[k].b) << k;
    for (int e = 0; e < 9; ++e) ASSERT_EQ(two[k].block(e), one[k].block(e)) << k;
  }
  // As pieces (shadow-H reflections read them so), after a block already there: that block,
  // then the same blocks in the same order, each chunk's in a piece of its own.
  const ThreadCount count(2);
  PairHessianPieces pieces;
  pieces.last().push_back({-1, -1, Eigen::Matrix3d::Identity()});
  ASSERT_TRUE(pair.pair_hessian_pieces(input.system, list, mask, pieces));
  EXPECT_EQ(pieces.used, 2u);
  std::vector<const PairHessian*> in_order;
  for (std::size_t k = 0; k < pieces.used; ++k) {
    for (const PairHessian& b : pieces.pieces[k]) in_order.push_back(&b);
  }
  ASSERT_EQ(in_order.size(), one.size() + 1);
  EXPECT_EQ(in_order[0]->a, -1);
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_EQ(in_order[k + 1]->a, one[k].a) << k;
    ASSERT_EQ(in_order[k + 1]->b, one[k].b) << k;
    for (int e = 0; e < 9; ++e) ASSERT_EQ(in_order[k + 1]->block(e), one[k].block(e)) << k;
  }
}
INSTANTIATE_TEST_SUITE_P(Threads, MaskedPairHessians, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "CellOrder" : "ListOrder";
                         });

TEST(Threads, OrderedSumOnOneChunkIsTheSerialSum) {
  std::vector<double> terms(5000);
  for (std::size_t i = 0; i < terms.size(); ++i) terms[i] = 1.0 / static_cast<double>(i + 1);
  double serial = 0.0;
  for (double t : terms) serial += t;
  const ThreadCount threads(1);
  EXPECT_EQ(ordered_sum<double>(terms.size(), [&](std::size_t i) { return terms[i]; }), serial);
}

// The splits' rule (core/parallel.hpp): a cheap loop's chunks hold at least
// cheap_chunk_minimum() items (512 by default), a cluster loop's at least
// cluster_chunk_minimum() rows (256) and one cluster, one chunk a thread at most; with
// [run] split_small_loops = false, 8192 and 1024 (2 threads then split from 16384 items and
// 2048 rows, deli's splits until stop 49).
TEST(Threads, ChunksHoldTheirMinimumAndAtMostOneAThread) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const int threads_before = thread_count();
  set_thread_count(8);
  EXPECT_EQ(cheap_chunk_minimum(), 512u);
  EXPECT_EQ(cluster_chunk_minimum(), 256u);
  EXPECT_EQ(chunks_for_cheap(0), 1);
  EXPECT_EQ(chunks_for_cheap(1023), 1);
  EXPECT_EQ(chunks_for_cheap(1024), 2);
  EXPECT_EQ(chunks_for_cheap(4000), 7);  // the 4000-sphere fluid: 571 items a chunk
  EXPECT_EQ(chunks_for_cheap(4096), 8);
  EXPECT_EQ(chunks_for_cheap(1000000), 8);
  EXPECT_EQ(chunks_for_work(30, 1170), 4);  // the default input's 30 chains, 1170 rods
  EXPECT_EQ(chunks_for_work(3, 100000), 3);
  EXPECT_EQ(chunks_for_work(1, 100000), 1);
  EXPECT_EQ(chunks_for_work(100, 511), 1);
  set_cheap_chunk_minimum(kUnsplitCheapChunk);
  set_cluster_chunk_minimum(kUnsplitClusterChunk);
  set_thread_count(2);
  EXPECT_EQ(chunks_for_cheap(16383), 1);
  EXPECT_EQ(chunks_for_cheap(16384), 2);
  EXPECT_EQ(chunks_for_work(100, 2047), 1);
  EXPECT_EQ(chunks_for_work(100, 2048), 2);
  set_cheap_chunk_minimum(512);
  set_cluster_chunk_minimum(256);
  set_thread_count(threads_before);
}

TEST(Threads, AChunksExceptionIsTheOneASerialLoopMeetsFirst) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const ThreadCount threads(2);
  try {
    for_each_chunk(100, 2, [](int c, std::size_t, std::size_t) {
      throw std::runtime_error("chunk " + std::to_string(c));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "chunk 0");
  }
}

// filter_in_order joins the items that pass in the serial loop's order, whatever the split:
// 1, 3 and 20 chunks (past the 16 per-chunk slots kept on the stack), items passing
// unevenly (none in some chunks, all in others).
TEST(Threads, FilterJoinsThePassingItemsInTheSerialOrder) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const ThreadCount threads(4);
  const std::size_t n = 5000;
  auto passes = [](std::size_t k) { return (k % 7 == 3) || (k >= 2000 && k < 2600) || k == n - 1; };
  std::vector<std::size_t> serial;
  for (std::size_t k = 0; k < n; ++k) {
    if (passes(k)) serial.push_back(k);
  }
  std::vector<std::uint32_t> scratch;
  for (const int chunks : {1, 3, 20}) {
    std::vector<std::size_t> joined;
    filter_in_order(n, chunks, scratch, passes, [&](std::size_t k) { joined.push_back(k); });
    EXPECT_EQ(joined, serial) << chunks << " chunks";
  }
}

// ordered_max_then: the serial maximum, and after() run once on every item's chunk, after
// the terms of that chunk (each item's output seen there).
TEST(Threads, OrderedMaxThenRunsAfterOnEveryChunkItsTermsWrote) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const ThreadCount threads(2);
  const std::size_t n = 4096;
  std::vector<double> term_of(n, 0.0), after_of(n, -1.0);
  const double largest = ordered_max_then(
      n, -1.0,
      [&](std::size_t i) {
        term_of[i] = static_cast<double>((i * 37) % 1001);
        return term_of[i];
      },
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) after_of[i] = 2.0 * term_of[i];
      });
  EXPECT_EQ(largest, 1000.0);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(after_of[i], 2.0 * term_of[i]) << i;
}

// The second pass of for_each_chunk_then reads what every chunk of the first wrote (the
// barrier between them), its chunk c on the thread of the first pass's chunk c.
TEST(Threads, ChunksThenSecondPassSeesTheWholeFirstPass) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const ThreadCount threads(2);
  const std::size_t n = 4096;
  std::vector<double> written(n, 0.0), read(n, -1.0);
  std::vector<int> first_thread(2, -1), second_thread(2, -2);
  for_each_chunk_then(
      n, n, 2,
      [&](int c, std::size_t begin, std::size_t end) {
        first_thread[static_cast<std::size_t>(c)] = team_thread();
        // Chunk 0 late: without the barrier chunk 1 would read its items unwritten.
        if (c == 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
        for (std::size_t i = begin; i < end; ++i) written[i] = static_cast<double>(i);
      },
      [&](int c, std::size_t begin, std::size_t end) {
        second_thread[static_cast<std::size_t>(c)] = team_thread();
        // Each item reads one the other chunk wrote.
        for (std::size_t i = begin; i < end; ++i) read[i] = written[n - 1 - i];
      });
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(read[i], static_cast<double>(n - 1 - i));
  EXPECT_EQ(first_thread, second_thread);
}

// A first-pass exception skips the second pass and is the one a serial loop meets first.
TEST(Threads, ChunksThenFirstPassExceptionSkipsTheSecond) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const ThreadCount threads(2);
  std::atomic<int> second{0};
  try {
    for_each_chunk_then(
        100, 100, 2,
        [](int c, std::size_t, std::size_t) {
          if (c == 1) throw std::runtime_error("chunk " + std::to_string(c));
        },
        [&](int, std::size_t, std::size_t) { ++second; });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "chunk 1");
  }
  EXPECT_EQ(second.load(), 0);
}

// Jobs of the team of every size from 1 to 4 threads in a random order, each with a barrier:
// every thread number runs once a job, thread 0 on the calling thread and thread t on the
// team's worker t (the same thread in every job), and after the barrier each sees what every
// thread of its job wrote before it. A worker that took a later job's fields for an earlier
// one's (a job handed only to the workers it runs on) would run a number twice or not at all.
TEST(Team, JobsOfEverySizeRunEachThreadOnceOnItsOwnWorker) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  constexpr int kMost = 4;
  std::mt19937 random(5);
  std::vector<std::thread::id> worker(kMost);
  for (int job = 0; job < 2000; ++job) {
    const int threads = 1 + static_cast<int>(random() % kMost);
    std::array<std::atomic<int>, kMost> runs{}, seen_after_barrier{};
    std::array<std::thread::id, kMost> ran_on{};
    std::array<std::atomic<int>, kMost> written{};
    auto body = [&](int t, int count) {
      // EXPECT: a thread returning before the barrier would leave the others waiting there.
      EXPECT_EQ(count, threads);
      EXPECT_EQ(team_thread(), t);
      ++runs[static_cast<std::size_t>(t)];
      ran_on[static_cast<std::size_t>(t)] = std::this_thread::get_id();
      written[static_cast<std::size_t>(t)].store(job + 1, std::memory_order_relaxed);
      team_barrier();
      int all = 0;
      for (int u = 0; u < count; ++u) {
        all += written[static_cast<std::size_t>(u)].load(std::memory_order_relaxed) == job + 1;
      }
      seen_after_barrier[static_cast<std::size_t>(t)] = all;
    };
    run_on_team(threads, body);
    for (int t = 0; t < kMost; ++t) {
      const auto k = static_cast<std::size_t>(t);
      ASSERT_EQ(runs[k].load(), t < threads ? 1 : 0) << "job " << job << " thread " << t;
      if (t >= threads) continue;
      ASSERT_EQ(seen_after_barrier[k].load(), threads) << "job " << job << " thread " << t;
      if (t == 0) {
        ASSERT_EQ(ran_on[k], std::this_thread::get_id());
      } else if (threads > 1) {
        if (worker[k] == std::thread::id{}) worker[k] = ran_on[k];
        ASSERT_EQ(ran_on[k], worker[k]) << "job " << job << " thread " << t;
      }
    }
  }
}

// The voluntary context switches of thread `tid` of this process so far (Linux).
long voluntary_switches(pid_t tid) {
  std::ifstream status("/proc/self/task/" + std::to_string(tid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("voluntary_ctxt_switches:", 0) == 0) return std::stol(line.substr(24));
  }
  return -1;
}

// A job of two threads on a team grown to four leaves workers 2 and 3 asleep: with waiting
// threads asleep (OMP_WAIT_POLICY=passive, the tests' policy), a worker woken for each job
// would switch in and out each time (100 jobs: about 100 switches each).
TEST(Team, AJobOfTwoThreadsLeavesTheOtherWorkersAsleep) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  if (!policy || std::string(policy) != "passive") GTEST_SKIP() << "workers asleep only if passive";
  constexpr int kMost = 4;
  std::array<pid_t, kMost> tid{};
  auto record = [&](int t, int) { tid[static_cast<std::size_t>(t)] = gettid(); };
  run_on_team(kMost, record);
  // Workers 2 and 3 asleep (they sleep at once when passive, but may not have got there yet).
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const long before2 = voluntary_switches(tid[2]), before3 = voluntary_switches(tid[3]);
  const long before1 = voluntary_switches(tid[1]);
  ASSERT_GE(before2, 0);
  ASSERT_GE(before3, 0);
  constexpr int kJobs = 100;
  std::atomic<int> on_worker_1{0};
  for (int job = 0; job < kJobs; ++job) {
    auto two = [&](int t, int) { on_worker_1 += t == 1; };
    run_on_team(2, two);
    // Time for the workers to fall asleep between jobs, as between a run's output steps.
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  EXPECT_EQ(on_worker_1.load(), kJobs);
  // Worker 1 did wake for them: the count sees wakes where they happen.
  EXPECT_GE(voluntary_switches(tid[1]) - before1, kJobs / 2);
  EXPECT_LT(voluntary_switches(tid[2]) - before2, 5);
  EXPECT_LT(voluntary_switches(tid[3]) - before3, 5);
}

// GVI's constraint phases on several threads: clusters solved and reflected on their own,
// per-particle passes split by particle, every sum the serial loop made joined in its
// order. Without pair forces nothing else is regrouped, so a trajectory on 2 threads is the
// one-thread trajectory bit for bit (the one-thread run being the serial code, bit for bit:
// tools/same_results.sh against main).
// Steps per run: 10, under the sanitizers 4 (support/short_runs.hpp). A step opens some
// twenty parallel regions, each costly where a loaded machine makes a waiting thread spin.
const int kGviSteps = testing::steps_or_prefix(10, 4);

struct GviTrajectory {
  std::vector<Vec3> position, velocity;
  double constraint_virial = 0.0;
  std::vector<std::pair<std::string, double>> statistics;
  // Each step's own (the frame sampler's, taken after every step): a term added in another
  // order changes a step's last bits, which the run's average can round away.
  std::vector<double> step_virials;
};

GviTrajectory run_gvi(const RunInput& input, int threads, int steps,
                      const GviOptions* options = nullptr) {
  const ThreadCount count(threads);
  System system = input.system;
  Gvi gvi(*input.force_field, input.constraints, options ? *options : input.gvi, system.particles);
  gvi.setup(system);
  std::vector<double> step_virials;
  for (int n = 0; n < steps; ++n) {
    gvi.step(system, n + 1 == steps);
    step_virials.push_back(gvi.take_constraint_virial(Sampler::frame));
    gvi.take_statistics(Sampler::frame);
  }
  return {system.particles.position, system.particles.velocity, gvi.take_constraint_virial(),
          gvi.take_statistics(), step_virials};
}

void expect_same_trajectory(const GviTrajectory& a, const GviTrajectory& b) {
  EXPECT_TRUE(same_bits(a.position, b.position));
  EXPECT_TRUE(same_bits(a.velocity, b.velocity));
  EXPECT_EQ(a.constraint_virial, b.constraint_virial);
  EXPECT_EQ(a.step_virials, b.step_virials);
  EXPECT_EQ(a.statistics, b.statistics);
}

// 40 random-walk chains of 30 beads held by rods (1160 rods, 40 clusters: past the rows
// from which the cluster loops are cut into chunks), free of pair forces.
RunInput rigid_chains() {
  return testing::thirty_bead_rod_chains("[forcefield.pair]\nstyle = \"none\"\n");
}

TEST(ThreadsGvi, RigidChainsOnTwoThreadsAreTheOneThreadTrajectory) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const RunInput input = rigid_chains();
  {
    const ThreadCount two(2);  // the cluster loops' split, as run_gvi's runs make it
    ASSERT_EQ(chunks_for_work(40, input.constraints.equalities.size()), 2);
  }
  const GviTrajectory one = run_gvi(input, 1, kGviSteps), two = run_gvi(input, 2, kGviSteps),
                      again = run_gvi(input, 2, kGviSteps);
  expect_same_trajectory(two, again);
  expect_same_trajectory(one, two);
  EXPECT_NE(one.constraint_virial, 0.0);
}

// On 4 threads the 1200 particles' passes and the 1160 rods' cluster loops run in 2 chunks
// (of at least 512 items and rows: ThreadCount), fewer than the threads: the same trajectory.
TEST(ThreadsGvi, RigidChainsOnFourThreadsInTwoChunksAreTheOneThreadTrajectory) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const RunInput input = rigid_chains();
  {
    const ThreadCount four(4);
    ASSERT_EQ(chunks_for_cheap(input.system.particles.size()), 2);
    ASSERT_EQ(chunks_for_work(40, input.constraints.equalities.size()), 2);
  }
  const GviTrajectory one = run_gvi(input, 1, kGviSteps), four = run_gvi(input, 4, kGviSteps);
  expect_same_trajectory(one, four);
  EXPECT_NE(one.constraint_virial, 0.0);
}

// The particles of chains 2k and 2k+1 (of `length` beads) interleaved, bead by bead: each
// chain's rods then join every other particle, and no cluster's particles are consecutive.
void interleave_chain_pairs(RunInput& input, std::size_t length) {
  Particles& P = input.system.particles;
  const std::size_t n = P.size();
  std::vector<std::int32_t> to(n);  // old index -> new
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t chain = i / length, bead = i % length, pair = chain / 2;
    to[i] = static_cast<std::int32_t>(pair * 2 * length + 2 * bead + chain % 2);
  }
  auto permute = [&](auto& values) {
    auto moved = values;
    for (std::size_t i = 0; i < n; ++i) moved[static_cast<std::size_t>(to[i])] = values[i];
    values = std::move(moved);
  };
  permute(P.position), permute(P.velocity), permute(P.mass), permute(P.radius);
  permute(P.type), permute(P.id), permute(P.molecule), permute(P.image);
  for (Constraint& c : input.constraints.equalities) c.i = to[c.i], c.j = to[c.j];
  for (auto* pairs :
       {&input.constraints.unconstrained_pairs, &input.constraints.always_checked_pairs}) {
    for (auto& [a, b] : *pairs) {
      a = to[a], b = to[b];
      if (a > b) std::swap(a, b);
    }
    std::sort(pairs->begin(), pairs->end());
  }
}

// A melt of rods alone (no pair forces, no contact rows, Verlet) steps cluster by cluster:
// the half kick, free step and end positions, then the kick and velocities, made with each
// chunk's solves (Gvi::steps_by_cluster). With the constrained predictor it steps by passes
// over every particle around the same solves: the predictor solves the rods for the step's
// own free step, which the position update then takes (ConstrainedIntegrator::
// SolvedEqualities). The two are one trajectory bit for bit (the statistics differ: the
// predictor's solves count too), with the chains' particles in order (clusters of
// consecutive particles, joined into runs) and interleaved (listed clusters). On 2 threads:
// one thread steps by passes.
TEST(ThreadsGvi, RodsAloneByClusterAreTheTrajectoryOfThePasses) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  for (const bool interleaved : {false, true}) {
    RunInput input = rigid_chains();
    if (interleaved) interleave_chain_pairs(input, 30);
    GviOptions passes = input.gvi;
    passes.constrained_predictor = true;
    SCOPED_TRACE(interleaved ? "interleaved" : "in order");
    const GviTrajectory by_cluster = run_gvi(input, 2, kGviSteps);
    const GviTrajectory by_passes = run_gvi(input, 2, kGviSteps, &passes);
    EXPECT_TRUE(same_bits(by_cluster.position, by_passes.position));
    EXPECT_TRUE(same_bits(by_cluster.velocity, by_passes.velocity));
    EXPECT_EQ(by_cluster.constraint_virial, by_passes.constraint_virial);
    EXPECT_NE(by_cluster.constraint_virial, 0.0);
  }
}

// The input's GVI trajectory on 1 thread, then twice on 2: all three the same bits. Returns
// the one-thread trajectory.
GviTrajectory expect_two_threads_repeat_one(const RunInput& input) {
  const GviTrajectory one = run_gvi(input, 1, kGviSteps), two = run_gvi(input, 2, kGviSteps),
                      again = run_gvi(input, 2, kGviSteps);
  expect_same_trajectory(two, again);
  expect_same_trajectory(one, two);
  return one;
}

// 1372 hard spheres (7^3 cells): 563 reflections in the first 10 steps from the lattice
// (deli run of the same input).
TEST(ThreadsGvi, HardSpheresOnTwoThreadsAreTheOneThreadTrajectory) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  const GviTrajectory one = expect_two_threads_repeat_one(testing::hard_sphere_fluid(7));
  const double reflected = testing::statistic(one.statistics, "reflected");
  if (!testing::short_runs()) EXPECT_GT(reflected, 0.0) << reflected;
}

// 4000 hard spheres (10^3 cells): about 1500 candidate rows a step, past the rows from which
// the active set's tests and the feasibility guard's scan are cut into chunks where the
// particles' passes are (the test's cheap-loop minimum is 1024 particles).
TEST(ThreadsGvi, FourThousandHardSpheresOnTwoThreadsAreTheOneThreadTrajectory) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  expect_two_threads_repeat_one(testing::hard_sphere_fluid(10));
}

// Without the feasibility guard, each step's end checks read the candidate rows themselves
// for the smallest gap (the guard's scan finds it otherwise): on two threads the rows the
// collection's second thread left in its own stretch are among them, and each step's
// smallest gap is the one thread's (untallied steps: no scan of every pair).
TEST(ThreadsGvi, HardSpheresWithoutTheGuardFindEachStepsSmallestGapOnTwoThreads) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  RunInput input = testing::hard_sphere_fluid(10);
  input.gvi.feasibility = Feasibility::none;
  auto smallest_gaps = [&](int threads) {
    const ThreadCount count(threads);
    System system = input.system;
    Gvi gvi(*input.force_field, input.constraints, input.gvi, system.particles);
    gvi.setup(system);
    gvi.take_statistics();
    std::vector<double> gaps;
    for (int n = 0; n < kGviSteps; ++n) {
      gvi.step(system, false);
      gaps.push_back(testing::statistic(gvi.take_statistics(), "min_gap"));
    }
    return gaps;
  };
  const std::vector<double> one = smallest_gaps(1);
  EXPECT_EQ(smallest_gaps(2), one);
  EXPECT_LT(*std::min_element(one.begin(), one.end()), 0.1);
}

// Without forces the midpoint Lagrangian's free step is Verlet's, bit for bit (the kick of a
// zero force adds zero), but after each reflection it makes the whole prediction again,
// where Verlet makes again only the reflected particles', on the threads that reflected them
// (Gvi::reflect_and_predict). The two trajectories are one: a reflected particle whose
// prediction was not made again (or not marked as changed) would leave a contact unseen in
// the active set's next round (dropping the shared clusters' particles from the predictions
// made again changes this trajectory). 4000 spheres at twice the step, on 1 and 2 threads.
TEST(ThreadsGvi, HardSpheresReflectedPredictionsAreTheWholePredictionMadeAgain) {
  RunInput input = testing::hard_sphere_fluid(10);
  input.gvi.timestep = 0.04;
  for (const int threads : {1, 2}) {
    if (threads > 1 && !kThreaded) continue;
    SCOPED_TRACE(threads);
    GviOptions midpoint = input.gvi;
    midpoint.lagrangian = Lagrangian::midpoint;
    ASSERT_EQ(input.gvi.lagrangian, Lagrangian::verlet);
    const GviTrajectory verlet = run_gvi(input, threads, kGviSteps);
    const GviTrajectory whole = run_gvi(input, threads, kGviSteps, &midpoint);
    EXPECT_TRUE(same_bits(verlet.position, whole.position));
    EXPECT_TRUE(same_bits(verlet.velocity, whole.velocity));
    EXPECT_EQ(verlet.constraint_virial, whole.constraint_virial);
    if (!testing::short_runs()) {
      EXPECT_GT(testing::statistic(verlet.statistics, "reflected"), 0.0);
    }
  }
}

// The 4000-sphere fluid at twice the step with its active set capped at `rounds` rounds: the
// same trajectory on one and two threads, with `left` (what the cap leaves) above zero.
void expect_capped_fluid_on_two_threads_repeats_one(int rounds, const char* left) {
  RunInput input = testing::hard_sphere_fluid(10);
  input.gvi.timestep = 0.04;
  input.constraints.limits.active_set_rounds = rounds;
  const GviTrajectory one = expect_two_threads_repeat_one(input);
  EXPECT_GT(testing::statistic(one.statistics, left), 0.0);
}

// One active-set round: a reflection can then send a sphere into a contact no prediction
// saw, and the feasibility guard lands the rows that overlap at the end positions (deli run of
// the same input: 49 landings in the first 4 steps, 6 of them in step 3). Its scan of the
// candidates at x runs in chunks on 2 threads; a row one chunk found and the join dropped
// would change the trajectory.
TEST(ThreadsGvi, HardSpheresTheGuardLandsOnTwoThreadsAreTheOneThreadTrajectory) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  expect_capped_fluid_on_two_threads_repeats_one(1, "landings");
}

// Three rounds (rounds that go on growing at this step): on two threads the rounds after the
// first run in the reflections' job while each finds rows and has a round after it for its
// test, the third on the calling thread. The same trajectory and caps as one thread's; a job
// that ran a round past the cap would reflect rows one thread leaves to the feasibility guard.
TEST(ThreadsGvi, HardSpheresActiveSetCappedOnTwoThreadsIsTheOneThreadTrajectory) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  expect_capped_fluid_on_two_threads_repeats_one(3, "active_set_caps");
}

// Reflections capped at one solve leave rows approaching; a later round of the active set
// reflects their clusters again, with the rows it adds. Against the path that reflects every
// cluster at every round (the shadow energy's, here without forces the Hamiltonian's kinetic
// form, every row through the general solve: the same impulses to round-off), after 40 steps
// of the 4000-sphere fluid at h = 0.02 (362 capped reflections). With the clusters left
// approaching not reflected again the velocities differ there by 0.25 (largest 4.2), and
// still agree to round-off after 20 steps: a shorter run would not tell.
TEST(ThreadsGvi, HardSpheresCappedReflectionsAreReflectedAgainByLaterRounds) {
  RunInput input = testing::hard_sphere_fluid(10);
  input.gvi.timestep = 0.02;
  input.constraints.limits.reflection_solves = 1;
  GviOptions every_cluster = input.gvi;
  every_cluster.energy = ReflectionEnergy::shadow;
  const int steps = 40;
  const GviTrajectory all = run_gvi(input, 1, steps, &every_cluster);
  // On two threads the chunks' threads walk from the seeds, the rows left approaching among
  // them.
  for (const int threads : {1, 2}) {
    if (threads > 1 && !kThreaded) continue;
    SCOPED_TRACE(threads);
    const GviTrajectory walked = run_gvi(input, threads, steps);
    EXPECT_GT(testing::statistic(walked.statistics, "stalled_reflections"), 0.0);
    double largest = 0.0, difference = 0.0;
    for (std::size_t i = 0; i < walked.velocity.size(); ++i) {
      largest = std::max(largest, norm(walked.velocity[i]));
      difference = std::max(difference, norm(walked.velocity[i] - all.velocity[i]));
    }
    EXPECT_LT(difference, 1e-9 * largest);
  }
}

// Two chains broken by a second rod of another length on one of their pairs, one in each
// half of the cluster list (so in different chunks on two threads): the run stops at the
// first, as a serial loop would, with the same message (and problem file) on 1 and 2 threads.
TEST(ThreadsGvi, AFailedSolveOnTwoThreadsNamesTheClusterOfOneThread) {
  if (!kThreaded) GTEST_SKIP() << "built without OpenMP";
  RunInput input = rigid_chains();
  const std::vector<Constraint> rods = input.constraints.equalities;
  for (const std::size_t k : {rods.size() / 4, 3 * rods.size() / 4}) {
    Constraint conflicting = rods[k];
    conflicting.length = 1.5;
    input.constraints.equalities.push_back(conflicting);
  }
  // The problem file goes to the working directory: a directory of this test's own.
  const testing::ScratchDirectory own("ThreadsGviFailure");
  auto failure = [&](int threads) {
    try {
      run_gvi(input, threads, 1);
    } catch (const SimulationError& e) {
      return std::string(e.what());
    }
    return std::string("no failure");
  };
  const std::string one = failure(1), two = failure(2);
  // The first broken chain's cluster, named by its first atom.
  std::string first_atom;
  for (const Cluster& cluster :
       find_clusters(input.constraints.equalities, input.system.particles.size())) {
    if (std::find(cluster.particles.begin(), cluster.particles.end(), rods[rods.size() / 4].i) !=
        cluster.particles.end()) {
      first_atom = "from atom " + std::to_string(input.system.particles.id[cluster.particles[0]]);
    }
  }
  EXPECT_NE(one.find("did not converge"), std::string::npos) << one;
  EXPECT_NE(one.find(first_atom + " ("), std::string::npos) << first_atom << ": " << one;
  EXPECT_EQ(one, two);
  EXPECT_TRUE(std::filesystem::exists("deli-failed-solve-step1.txt"));
}

}  // namespace
}  // namespace deli
