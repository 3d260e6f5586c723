// LAMMPS' special_bonds lj rule (the LAMMPS manual, special_bonds): on a linear chain
// 0-1-2-3-4, a factor of 1 keeps a separation's pairs ordinary, 0 excludes them, and a
// factor between excludes them from the neighbour list to be computed scaled.
#include "forces/special_bonds.hpp"

#include <gtest/gtest.h>

namespace deli {
namespace {

SpecialPairs chain_of_five() {
  Topology topology;
  for (std::int32_t i = 0; i < 4; ++i) topology.bonds.push_back({i, i + 1, 0});
  return find_special_pairs(topology, 5);
}

TEST(SpecialBonds, FactorOneKeepsZeroExcludesBetweenScales) {
  const std::vector<ExcludedSpecialPair> excluded =
      excluded_special_pairs(chain_of_five(), {0.0, 0.5, 1.0});
  // 4 bonded pairs (factor 0), then 3 pairs two bonds apart (0.5); 1-4 pairs stay.
  ASSERT_EQ(excluded.size(), 7u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(excluded[k].separation, 1);
    EXPECT_EQ(excluded[k].j, excluded[k].i + 1);
    EXPECT_FALSE(excluded[k].scaled());
  }
  for (std::size_t k = 4; k < 7; ++k) {
    EXPECT_EQ(excluded[k].separation, 2);
    EXPECT_EQ(excluded[k].j, excluded[k].i + 2);
    EXPECT_TRUE(excluded[k].scaled());
    EXPECT_EQ(excluded[k].factor, 0.5);
  }
}

TEST(SpecialBonds, LammpsDefaultExcludesAllThreeNeighbours) {
  const std::vector<ExcludedSpecialPair> excluded =
      excluded_special_pairs(chain_of_five(), {0.0, 0.0, 0.0});
  ASSERT_EQ(excluded.size(), 9u);  // 4 + 3 + 2
  EXPECT_EQ(excluded.back().separation, 3);
  EXPECT_EQ(excluded.back().i, 1);
  EXPECT_EQ(excluded.back().j, 4);
  EXPECT_TRUE(excluded_special_pairs(chain_of_five(), {1.0, 1.0, 1.0}).empty());
}

}  // namespace
}  // namespace deli
