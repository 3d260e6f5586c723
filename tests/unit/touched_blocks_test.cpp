// The blocks each chunk of the pair loop touches (NeighborList::touched_blocks), and the
// pair loop that gathers positions and adds forces on those blocks alone. Expected values:
// the blocks found from the list by particle, pair by pair (a second method), and the
// forces of the same list on one thread (the same pairs, the additions grouped otherwise:
// round-off).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/parallel.hpp"
#include "input/run_input.hpp"
#include "neighbor/neighbor_list.hpp"
#include "support/test_systems.hpp"
#include "support/thread_count.hpp"

namespace deli {
namespace {

using testing::ThreadCount;

// The LJ liquid of 4000 atoms on its fcc lattice, in the lattice's index order (layer by
// layer), jiggled: each half of the indices is a slab of the box, and its pairs reach only
// the slabs' boundaries in the other half, so a chunk touches some blocks and not others.
RunInput lattice_liquid() {
  RunInput input = load_run_input(DELI_SOURCE_DIR "/inputs/lj_liquid/lj_4000.toml");
  testing::jiggle(input.system.particles, 0.05, 17);
  return input;
}

NeighborList list_for(const RunInput& input, bool cell_order) {
  NeighborList list(input.force_field->neighbor_cutoff(), 0.3);
  list.set_exclusions({});
  list.set_cell_order(cell_order);
  list.build(input.system.particles.position, input.system.box);
  return list;
}

// Chunk c's blocks, pair by pair from the list by particle (items renamed to slots with cell
// order on): its items' own blocks (the items of pair_chunk_starts' chunk c) and their
// partners'.
std::set<std::size_t> blocks_by_pairs(const NeighborList& list, int c, int chunks) {
  const std::vector<std::int32_t>& slot_particle = list.cell_ordered().particle;
  const std::size_t n = list.offsets().size() - 1;
  std::vector<std::size_t> slot_of(n);
  for (std::size_t i = 0; i < n; ++i) slot_of[i] = i;
  for (std::size_t s = 0; s < slot_particle.size(); ++s) {
    slot_of[static_cast<std::size_t>(slot_particle[s])] = s;
  }
  std::set<std::size_t> blocks;
  const std::vector<std::size_t>& starts = list.pair_chunk_starts(chunks);
  const IndexRange own{starts[static_cast<std::size_t>(c)],
                       starts[static_cast<std::size_t>(c) + 1]};
  for (std::size_t i = 0; i < n; ++i) {
    if (slot_of[i] < own.begin || slot_of[i] >= own.end) continue;
    blocks.insert(TouchedBlocks::block_of(slot_of[i]));
    for (std::size_t k = list.offsets()[i]; k < list.offsets()[i + 1]; ++k) {
      blocks.insert(
          TouchedBlocks::block_of(slot_of[static_cast<std::size_t>(list.neighbors()[k])]));
    }
  }
  return blocks;
}

void expect_blocks_of_the_pairs(bool cell_order) {
  const RunInput input = lattice_liquid();
  for (const int threads : {1, 2}) {
    const ThreadCount count(threads);
    const NeighborList list = list_for(input, cell_order);
    for (const int chunks : {2, 3}) {
      const TouchedBlocks& touched = list.touched_blocks(chunks);
      ASSERT_EQ(touched.chunks(), chunks);
      const std::size_t blocks = TouchedBlocks::block_of(input.system.particles.size() - 1) + 1;
      std::size_t left_out = 0;
      for (int c = 0; c < chunks; ++c) {
        const std::set<std::size_t> expected = blocks_by_pairs(list, c, chunks);
        std::set<std::size_t> marked, in_runs;
        for (std::size_t b = 0; b < blocks; ++b) {
          if (touched.touches(c, b)) marked.insert(b);
        }
        for (const TouchedBlocks::Run& run : touched.runs(c)) {
          ASSERT_LT(run.begin, run.end);
          for (std::size_t s = run.begin; s < run.end; ++s) {
            in_runs.insert(TouchedBlocks::block_of(s));
          }
        }
        EXPECT_EQ(marked, expected) << "chunk " << c << " of " << chunks;
        EXPECT_EQ(in_runs, expected) << "chunk " << c << " of " << chunks;
        left_out += blocks - expected.size();
      }
      // The case the blocks are for: chunks that do not touch every block.
      EXPECT_GT(left_out, 0u);
    }
  }
}

// The pair loop's chunks with cell order on hold equal numbers of listed pairs, to within one
// slot's pairs (the slots are whole), counted from the list by particle; without cell order,
// chunk_range's equal counts of particles.
TEST(TouchedBlocks, PairChunksHoldEqualPairCounts) {
  const RunInput input = lattice_liquid();
  for (const bool cell_order : {true, false}) {
    const NeighborList list = list_for(input, cell_order);
    const std::size_t n = input.system.particles.size();
    for (const int chunks : {2, 3}) {
      const std::vector<std::size_t>& starts = list.pair_chunk_starts(chunks);
      ASSERT_EQ(starts.size(), static_cast<std::size_t>(chunks) + 1);
      EXPECT_EQ(starts.front(), 0u);
      EXPECT_EQ(starts.back(), n);
      if (!cell_order) {
        for (int c = 0; c < chunks; ++c) EXPECT_EQ(starts[c], chunk_range(n, c, chunks).begin);
        continue;
      }
      // Pairs by slot from the list by particle.
      std::vector<std::size_t> pairs_of_slot(n, 0);
      const std::vector<std::int32_t>& slot_particle = list.cell_ordered().particle;
      std::size_t most = 0;
      for (std::size_t s = 0; s < n; ++s) {
        const auto i = static_cast<std::size_t>(slot_particle[s]);
        pairs_of_slot[s] = list.offsets()[i + 1] - list.offsets()[i];
        most = std::max(most, pairs_of_slot[s]);
      }
      const std::size_t total = list.pair_count();
      for (int c = 0; c < chunks; ++c) {
        std::size_t in_chunk = 0;
        for (std::size_t s = starts[c]; s < starts[c + 1]; ++s) in_chunk += pairs_of_slot[s];
        EXPECT_NEAR(static_cast<double>(in_chunk), static_cast<double>(total) / chunks,
                    static_cast<double>(most))
            << "chunk " << c << " of " << chunks;
      }
    }
  }
}

TEST(TouchedBlocks, AreTheBlocksOfEachChunksItemsAndTheirPartners) {
  expect_blocks_of_the_pairs(false);
}

TEST(TouchedBlocks, WithCellOrderAreTheBlocksOfEachChunksSlotsAndTheirPartners) {
  expect_blocks_of_the_pairs(true);
}

// The pair loop on two threads, where each chunk gathers positions and zeroes forces on its
// touched blocks alone and the chunks' forces are added block by block: the same forces as
// one thread to round-off, the same bits on every two-thread evaluation.
TEST(TouchedBlocks, PairForcesOnTwoThreadsRepeatAndAgreeWithOneToRoundOff) {
  if (!testing::kThreaded) GTEST_SKIP() << "built without OpenMP";
  const RunInput input = lattice_liquid();
  testing::Evaluated one, two, again;
  {
    const ThreadCount threads(1);
    one = testing::evaluate(input, 0.3);
  }
  {
    const ThreadCount threads(2);
    ASSERT_GT(chunks_for_cheap(input.system.particles.size()), 1);
    two = testing::evaluate(input, 0.3);
    again = testing::evaluate(input, 0.3);
  }
  double largest = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < one.force.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(two.force[i][a], again.force[i][a]);
      largest = std::max(largest, std::abs(one.force[i][a]));
      worst = std::max(worst, std::abs(one.force[i][a] - two.force[i][a]));
    }
  }
  // Some 40 pair terms a force, up to ~100 in size at the lattice's jiggled distances: a
  // regrouping moves a force by a few ulps of that.
  EXPECT_LT(worst, 1e-12 * largest);
  EXPECT_GT(largest, 1.0);
  EXPECT_EQ(two.evaluation.potential, again.evaluation.potential);
  EXPECT_NEAR(two.evaluation.potential, one.evaluation.potential,
              1e-13 * std::abs(one.evaluation.potential));
  EXPECT_NEAR(two.evaluation.virial.trace(), one.evaluation.virial.trace(),
              1e-13 * std::abs(one.evaluation.virial.trace()));
}

}  // namespace
}  // namespace deli
