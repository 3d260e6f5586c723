// Cache order ([neighbor] cell_order): the neighbour list also kept by slot in cell order,
// and the pair loop run on positions gathered into that order. Expected values: the same
// force field through the list by particle (the pairs are the same pairs, only the order
// of the additions differs: round-off), and the list by particle itself (the list by slot
// is that list, renamed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "forces/special_bonds.hpp"
#include "input/run_input.hpp"
#include "integrators/force_engine.hpp"
#include "neighbor/neighbor_list.hpp"
#include "support/test_systems.hpp"
#include "support/thread_count.hpp"

namespace deli {
namespace {

// 100 harmonic chains of 40 beads with shifted LJ (bonded exclusions), jiggled and
// wrapped into the box as a run does before each build (the list then has image codes).
RunInput wrapped_chain_melt() {
  RunInput input = load_run_input(DELI_SOURCE_DIR "/inputs/lj_chains/chains_4000_harmonic.toml");
  Particles& p = input.system.particles;
  testing::jiggle(p, 0.05, 13);
  for (std::size_t i = 0; i < p.size(); ++i) input.system.box.wrap(p.position[i], p.image[i]);
  return input;
}

NeighborList list_for(const RunInput& input, bool cell_order) {
  NeighborList list(input.force_field->neighbor_cutoff(), 0.3);
  const SpecialPairs special =
      find_special_pairs(input.system.topology, input.system.particles.size());
  list.set_exclusions(special_exclusions(special, input.force_field->special_lj));
  list.set_cell_order(cell_order);
  list.build(input.system.particles.position, input.system.box);
  return list;
}

TEST(CellOrder, TheListBySlotIsTheListByParticleRenamed) {
  const RunInput input = wrapped_chain_melt();
  const NeighborList plain = list_for(input, false), sorted = list_for(input, true);
  // The list by particle does not depend on the option.
  EXPECT_EQ(sorted.neighbors(), plain.neighbors());
  EXPECT_EQ(sorted.offsets(), plain.offsets());
  EXPECT_EQ(sorted.image_codes(), plain.image_codes());
  ASSERT_FALSE(plain.image_codes().empty());
  EXPECT_TRUE(plain.cell_ordered().particle.empty());

  const NeighborList::CellOrdered& by_slot = sorted.cell_ordered();
  const std::size_t n = input.system.particles.size();
  // A permutation of the particles.
  std::vector<std::int32_t> seen = by_slot.particle;
  std::sort(seen.begin(), seen.end());
  std::vector<std::int32_t> all(n);
  std::iota(all.begin(), all.end(), 0);
  ASSERT_EQ(seen, all);
  // Slot s lists, renamed back through the permutation, particle[s]'s partners in order.
  ASSERT_EQ(by_slot.offsets.size(), n + 1);
  ASSERT_EQ(by_slot.neighbors.size(), plain.neighbors().size());
  ASSERT_EQ(by_slot.image_codes.size(), plain.image_codes().size());
  for (std::size_t s = 0; s < n; ++s) {
    const auto i = static_cast<std::size_t>(by_slot.particle[s]);
    ASSERT_EQ(by_slot.offsets[s + 1] - by_slot.offsets[s],
              plain.offsets()[i + 1] - plain.offsets()[i]);
    for (std::size_t k = by_slot.offsets[s], m = plain.offsets()[i]; k < by_slot.offsets[s + 1];
         ++k, ++m) {
      ASSERT_EQ(by_slot.particle[static_cast<std::size_t>(by_slot.neighbors[k])],
                plain.neighbors()[m]);
      ASSERT_EQ(by_slot.image_codes[k], plain.image_codes()[m]);
    }
  }
  // Cell order: slots in non-decreasing cell, so consecutive slots are neighbours in space
  // (checked loosely: the mean distance between consecutive slots is under a cell's
  // diagonal, while in index order it is a chain bond, ~1; in random order, ~box/2).
  double sum = 0.0;
  const std::vector<Vec3>& x = input.system.particles.position;
  for (std::size_t s = 1; s < n; ++s) {
    sum +=
        norm(input.system.box.minimum_image(x[by_slot.particle[s]] - x[by_slot.particle[s - 1]]));
  }
  EXPECT_LT(sum / static_cast<double>(n - 1), 2.0);
}

// Ranges of a list (NeighborList::PartnerRanges) joined in particle order: the list by
// particle they stand for.
struct JoinedRanges {
  std::vector<std::int32_t> partners;
  std::vector<std::uint8_t> codes;
  std::vector<std::size_t> offsets{0};
};
JoinedRanges join(const NeighborList::PartnerRanges& ranges, std::size_t n) {
  EXPECT_EQ(ranges.particles, n);
  JoinedRanges out;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_LE(ranges.begin[i], ranges.end[i]);
    out.partners.insert(out.partners.end(), ranges.neighbors + ranges.begin[i],
                        ranges.neighbors + ranges.end[i]);
    out.codes.insert(out.codes.end(), ranges.image_codes + ranges.begin[i],
                     ranges.image_codes + ranges.end[i]);
    out.offsets.push_back(out.partners.size());
  }
  return out;
}

// Without cell order the force loop and the contact rows' scan read the list where the build
// left it (built_order()), and the list by particle is copied from there when first asked for:
// particle i's range there is its list by particle, entry for entry, on one thread and on two
// (the build's chunks joined). With cell order there is no such list, and partner_ranges()
// gives the list by particle itself.
TEST(CellOrder, TheBuiltOrderRangesAreTheListByParticle) {
  const RunInput input = wrapped_chain_melt();
  const std::size_t n = input.system.particles.size();
  for (const int threads : {1, 2}) {
    if (threads == 2 && !testing::kThreaded) continue;
    const testing::ThreadCount count(threads);
    const NeighborList plain = list_for(input, false);
    const NeighborList::PartnerRanges built = plain.built_order();
    ASSERT_NE(built.begin, nullptr);
    ASSERT_NE(built.image_codes, nullptr);
    EXPECT_EQ(plain.partner_ranges().begin, built.begin);
    // Read before the list by particle is made from the same arrays.
    const JoinedRanges joined = join(built, n);
    EXPECT_EQ(joined.partners, plain.neighbors()) << threads << " threads";
    EXPECT_EQ(joined.codes, plain.image_codes());
    EXPECT_EQ(joined.offsets, plain.offsets());
    EXPECT_EQ(joined.partners.size(), plain.pair_count());

    const NeighborList sorted = list_for(input, true);
    EXPECT_EQ(sorted.built_order().begin, nullptr);
    const JoinedRanges by_particle = join(sorted.partner_ranges(), n);
    EXPECT_EQ(by_particle.partners, plain.neighbors());
    EXPECT_EQ(by_particle.codes, plain.image_codes());
    EXPECT_EQ(by_particle.offsets, plain.offsets());
  }
}

TEST(CellOrder, ForcesAgreeWithTheListByParticleToRoundOffAndRepeatBitForBit) {
  const RunInput input = wrapped_chain_melt();
  const NeighborList plain = list_for(input, false), sorted = list_for(input, true);
  std::vector<Vec3> f_plain, f_sorted, f_again;
  const ForceEvaluation e_plain = input.force_field->compute(input.system, plain, f_plain);
  const ForceEvaluation e_sorted = input.force_field->compute(input.system, sorted, f_sorted);
  const ForceEvaluation e_again = input.force_field->compute(input.system, sorted, f_again);
  ASSERT_EQ(f_sorted.size(), f_plain.size());
  double largest = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < f_plain.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      largest = std::max(largest, std::abs(f_plain[i][a]));
      worst = std::max(worst, std::abs(f_plain[i][a] - f_sorted[i][a]));
      ASSERT_EQ(f_sorted[i][a], f_again[i][a]);
    }
  }
  // Each force a sum of some 40 terms of size up to ~100 (bonds): a few ulps of that size.
  EXPECT_LT(worst, 1e-12 * largest);
  EXPECT_NEAR(e_sorted.potential, e_plain.potential, 1e-13 * std::abs(e_plain.potential));
  EXPECT_NEAR(e_sorted.virial.trace(), e_plain.virial.trace(),
              1e-13 * std::abs(e_plain.virial.trace()));
  EXPECT_EQ(e_sorted.potential, e_again.potential);
}

// An LJ liquid's input without [neighbor] (the tests below add it).
const std::string kLjInput = R"(
[system]
[system.lattice]
type = "fcc"
density = 0.8442
cells = [4, 4, 4]
[forcefield.pair]
style = "lj/cut"
cutoff = 2.5
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]
[integrator]
timestep = 0.005
[run]
steps = 0
)";

TEST(CellOrder, TheInputOptionReachesTheForceEngine) {
  RunInput input = testing::input_from(kLjInput + "[neighbor]\nskin = 0.3\ncell_order = true\n");
  ASSERT_TRUE(input.force_field->cell_order);
  testing::jiggle(input.system.particles, 0.05, 14);
  ForceEngine engine(*input.force_field, input.skin);
  engine.compute(input.system);
  EXPECT_EQ(engine.neighbors().cell_ordered().particle.size(), input.system.particles.size());
  // A box under three reaches wide: no image codes, minimum images in the loop; the same
  // forces as through the list by particle, to round-off.
  EXPECT_TRUE(engine.neighbors().image_codes().empty());
  const NeighborList plain = list_for(input, false);
  std::vector<Vec3> f_plain;
  input.force_field->compute(input.system, plain, f_plain);
  for (std::size_t i = 0; i < f_plain.size(); ++i) {
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(engine.force()[i][a], f_plain[i][a], 1e-12);
  }
}

// On by default where the force field has a pair loop, as LAMMPS sorts its atoms unless told
// not to; off for hard spheres alone (nothing to gain, the list's copy by particle to pay);
// the key overrides either way.
TEST(CellOrder, OnByDefaultWhereAPairLoopRuns) {
  const std::string& lj = kLjInput;
  EXPECT_TRUE(testing::input_from(lj).force_field->cell_order);
  EXPECT_TRUE(testing::input_from(lj + "[neighbor]\nskin = 0.3\n").force_field->cell_order);
  EXPECT_FALSE(
      testing::input_from(lj + "[neighbor]\ncell_order = false\n").force_field->cell_order);
  const std::string spheres = R"(
[system]
[system.lattice]
type = "fcc"
density = 0.5
cells = [4, 4, 4]
[forcefield.pair]
style = "none"
[constraints]
hard_spheres = { diameter = 1.0 }
[integrator]
type = "gvi"
lagrangian = "verlet"
timestep = 0.005
[run]
steps = 0
)";
  EXPECT_FALSE(testing::input_from(spheres).force_field->cell_order);
  EXPECT_TRUE(
      testing::input_from(spheres + "[neighbor]\ncell_order = true\n").force_field->cell_order);
}

}  // namespace
}  // namespace deli
