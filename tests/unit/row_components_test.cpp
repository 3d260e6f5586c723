#include "constraints/row_components.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "constraints/clusters.hpp"

namespace deli {
namespace {

// Random pair rows (and some wall rows, j = -1) among `particles` particles.
std::vector<Constraint> random_rows(std::mt19937& random, std::size_t count, int particles) {
  std::uniform_int_distribution<int> particle(0, particles - 1);
  std::vector<Constraint> rows;
  for (std::size_t k = 0; k < count; ++k) {
    Constraint c;
    c.i = particle(random);
    c.j = k % 7 == 3 ? -1 : particle(random);
    if (c.j == c.i) c.j = (c.i + 1) % particles;
    rows.push_back(c);
  }
  return rows;
}

// Against find_clusters over every row (a second method: union-find from scratch), rows
// added in batches as the active set's rounds add them: each component visited holds a seed
// and is exactly one cluster's rows, each such cluster once, and no other.
TEST(GrowingRowComponents, AreTheClustersHoldingTheSeedsAsRowsAreAdded) {
  std::mt19937 random(11);
  GrowingRowComponents components;
  for (int list = 0; list < 6; ++list) {
    const int particles = 40 + 30 * list;
    std::vector<Constraint> rows;
    components.restart(static_cast<std::size_t>(particles));
    for (int batch = 0; batch < 5; ++batch) {
      SCOPED_TRACE(::testing::Message() << "list " << list << " batch " << batch);
      const std::size_t first_new = rows.size();
      EXPECT_EQ(components.continues(static_cast<std::size_t>(particles), first_new),
                first_new > 0);
      const std::vector<Constraint> added =
          random_rows(random, batch == 0 ? 25 : 1 + batch * list % 4, particles);
      rows.insert(rows.end(), added.begin(), added.end());
      components.link(rows);
      ASSERT_EQ(components.linked(), rows.size());
      // Seeds: the added rows, and some earlier ones (twice where both), in no order.
      std::vector<std::int32_t> seeds;
      for (std::size_t r = rows.size(); r-- > first_new;) seeds.push_back(static_cast<int>(r));
      for (std::size_t r = 0; r < first_new; r += 5) seeds.push_back(static_cast<int>(r));
      seeds.insert(seeds.end(), seeds.begin(), seeds.begin() + 2);

      const std::vector<Cluster> clusters =
          find_clusters(rows, static_cast<std::size_t>(particles));
      std::vector<int> cluster_of_row(rows.size(), -1);
      for (std::size_t c = 0; c < clusters.size(); ++c) {
        for (const std::int32_t r : clusters[c].rows) cluster_of_row[r] = static_cast<int>(c);
      }
      std::set<int> expected;
      for (const std::int32_t s : seeds) expected.insert(cluster_of_row[s]);

      std::set<int> visited;
      components.components_of(
          seeds.data(), seeds.size(), [&](const std::int32_t* found, std::size_t count) {
            std::vector<std::int32_t> component(found, found + count);
            std::sort(component.begin(), component.end());
            const int c = cluster_of_row[component.front()];
            EXPECT_EQ(component, clusters[c].rows);
            EXPECT_TRUE(visited.insert(c).second) << "cluster " << c << " visited twice";
          });
      EXPECT_EQ(visited, expected);
    }
  }
}

// Linked in parts (the particles split in two ranges, the upper linked first, as threads may),
// the links are link()'s: walked by two walkers, each with its own marks (the second after
// the first has marked every row), the components are link()'s in the order link()'s walk
// finds them, row by row.
TEST(GrowingRowComponents, LinkedInPartsAndWalkedByTwoWalkersAreTheOneLink) {
  std::mt19937 random(17);
  GrowingRowComponents whole, parts;
  GrowingRowComponents::Walker first, second;
  using Found = std::vector<std::vector<std::int32_t>>;
  auto walk = [](auto&& components_of, const std::vector<std::int32_t>& seeds) {
    Found found;
    components_of(seeds, [&](const std::int32_t* rows, std::size_t count) {
      found.emplace_back(rows, rows + count);
    });
    return found;
  };
  for (int list = 0; list < 4; ++list) {
    const int particles = 50 + 40 * list;
    const std::int32_t cut = particles / 3 + list;
    std::vector<Constraint> rows;
    whole.restart(static_cast<std::size_t>(particles));
    parts.restart(static_cast<std::size_t>(particles));
    for (int batch = 0; batch < 4; ++batch) {
      SCOPED_TRACE(::testing::Message() << "list " << list << " batch " << batch);
      const std::size_t first_new = rows.size();
      const std::vector<Constraint> added = random_rows(random, batch == 0 ? 30 : 3, particles);
      rows.insert(rows.end(), added.begin(), added.end());
      whole.link(rows);
      parts.begin_link(rows.size());
      parts.link_ends_at(rows, cut, particles);
      parts.link_ends_at(rows, 0, cut);
      parts.end_link(rows.size());
      ASSERT_EQ(parts.linked(), rows.size());
      std::vector<std::int32_t> seeds;
      for (std::size_t r = first_new; r < rows.size(); ++r) seeds.push_back(static_cast<int>(r));
      for (std::size_t r = 0; r < first_new; r += 4) seeds.push_back(static_cast<int>(r));
      const Found expected =
          walk([&](const std::vector<std::int32_t>& s,
                   auto&& visit) { whole.components_of(s.data(), s.size(), visit); },
               seeds);
      for (GrowingRowComponents::Walker* walker : {&first, &second}) {
        const Found found =
            walk([&](const std::vector<std::int32_t>& s,
                     auto&& visit) { parts.components_of(*walker, s.data(), s.size(), visit); },
                 seeds);
        EXPECT_EQ(found, expected);
      }
      EXPECT_FALSE(expected.empty());
    }
  }
}

// A restart forgets the rows linked: a particle's links to the rows before it are gone, even
// where their row ends are numbers the new rows' ends also take.
TEST(GrowingRowComponents, ARestartForgetsTheRowsLinked) {
  auto rows_of = [](std::vector<std::pair<int, int>> pairs) {
    std::vector<Constraint> rows(pairs.size());
    for (std::size_t k = 0; k < pairs.size(); ++k)
      rows[k].i = pairs[k].first, rows[k].j = pairs[k].second;
    return rows;
  };
  GrowingRowComponents components;
  components.restart(8);
  components.link(rows_of({{0, 1}, {1, 2}, {0, 2}}));
  EXPECT_TRUE(components.continues(8, 3));
  components.restart(8);
  EXPECT_FALSE(components.continues(8, 3));
  // None of these shares a particle with another; particles 0 and 2 were linked before.
  components.link(rows_of({{5, 6}, {2, 3}, {0, 4}}));
  const std::vector<std::int32_t> seeds = {0, 1, 2};
  std::vector<std::size_t> sizes;
  components.components_of(seeds.data(), seeds.size(),
                           [&](const std::int32_t*, std::size_t count) { sizes.push_back(count); });
  EXPECT_EQ(sizes, (std::vector<std::size_t>{1, 1, 1}));
}

}  // namespace
}  // namespace deli
