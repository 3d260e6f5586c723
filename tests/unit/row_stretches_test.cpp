// RowStretches (constraints/row_stretches.hpp) against the vector its stretches join into:
// row k and its gap by index and by for_each over any range, across empty stretches and
// stretch ends, and join() the concatenation itself.
#include "constraints/row_stretches.hpp"

#include <gtest/gtest.h>

#include "support/constraint_rows.hpp"

namespace deli {
namespace {

using testing::pair_row;

TEST(RowStretches, ReadAsTheirConcatenation) {
  // Stretches of 3, 0, 1, 0 and 4 rows: pair (k, k + 1) with gap k / 10 for row k of the whole.
  const std::vector<std::size_t> sizes = {3, 0, 1, 0, 4};
  std::vector<std::vector<Constraint>> rows(sizes.size());
  std::vector<std::vector<double>> gaps(sizes.size());
  std::vector<Constraint> whole;
  std::vector<double> whole_gaps;
  for (std::size_t s = 0; s < sizes.size(); ++s) {
    for (std::size_t m = 0; m < sizes[s]; ++m) {
      const auto k = static_cast<std::int32_t>(whole.size());
      rows[s].push_back(pair_row(ConstraintKind::sphere_pair, k, k + 1, 1.0));
      gaps[s].push_back(0.1 * k);
      whole.push_back(rows[s].back());
      whole_gaps.push_back(gaps[s].back());
    }
  }
  RowStretches stretches;
  stretches.assign(rows[0], gaps[0]);
  for (std::size_t s = 1; s < sizes.size(); ++s) stretches.add(rows[s], gaps[s]);
  ASSERT_EQ(stretches.size(), whole.size());
  EXPECT_EQ(stretches.stretches(), sizes.size());
  for (std::size_t k = 0; k < whole.size(); ++k) {
    EXPECT_EQ(stretches[k].i, whole[k].i) << "row " << k;
    EXPECT_EQ(stretches.gap(k), whole_gaps[k]) << "row " << k;
  }
  // Every range [begin, end): each row once, in order, with its own gap.
  for (std::size_t begin = 0; begin <= whole.size(); ++begin) {
    for (std::size_t end = begin; end <= whole.size(); ++end) {
      std::vector<std::size_t> seen;
      stretches.for_each(begin, end, [&](std::size_t k, const Constraint& row, double gap) {
        EXPECT_EQ(row.i, whole[k].i);
        EXPECT_EQ(gap, whole_gaps[k]);
        seen.push_back(k);
      });
      ASSERT_EQ(seen.size(), end - begin) << begin << ".." << end;
      for (std::size_t m = 0; m < seen.size(); ++m) EXPECT_EQ(seen[m], begin + m);
    }
  }
  std::vector<Constraint> joined(2, pair_row(ConstraintKind::rod, 9, 8, 2.0));  // replaced
  std::vector<double> joined_gaps(5, -1.0);
  stretches.join(joined, joined_gaps);
  ASSERT_EQ(joined.size(), whole.size());
  for (std::size_t k = 0; k < whole.size(); ++k) EXPECT_EQ(joined[k].i, whole[k].i);
  EXPECT_EQ(joined_gaps, whole_gaps);
  // One stretch again: the others are gone.
  stretches.assign(rows[2], gaps[2]);
  ASSERT_EQ(stretches.size(), 1u);
  EXPECT_EQ(stretches[0].i, 3);
}

}  // namespace
}  // namespace deli
