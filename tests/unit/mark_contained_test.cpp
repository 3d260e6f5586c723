// mark_contained (constrained_integrator.hpp) against its definition, contains() per
// candidate: rows that share particles (two walls of one particle, a pair and a rod on the
// same two particles, a pair listed as (j, i)) are told apart by the whole row.
#include <gtest/gtest.h>

#include "integrators/constrained_integrator.hpp"
#include "support/constraint_rows.hpp"

namespace deli {
namespace {

using testing::pair_row;
using testing::plane_row;

TEST(MarkContained, AgreesWithContainsRowByRow) {
  const std::vector<Constraint> rows = {pair_row(ConstraintKind::sphere_pair, 3, 7, 1.0),
                                        plane_row(2, {0, 0, 0}, {0, 0, 1}),
                                        pair_row(ConstraintKind::sphere_pair, 0, 1, 1.0),
                                        plane_row(2, {0, 0, 5}, {0, 0, -1}),
                                        pair_row(ConstraintKind::rod, 4, 5, 1.0),
                                        pair_row(ConstraintKind::sphere_pair, 9, 2, 0.8)};
  const std::vector<Constraint> candidates = {
      pair_row(ConstraintKind::sphere_pair, 0, 1, 1.0),   // held
      pair_row(ConstraintKind::sphere_pair, 1, 0, 1.0),   // the same particles the other way
      plane_row(2, {0, 0, 5}, {0, 0, -1}),                // the second of particle 2's walls
      plane_row(2, {0, 0, 5}, {0, 0, 1}),                 // another normal
      plane_row(3, {0, 0, 0}, {0, 0, 1}),                 // another particle
      pair_row(ConstraintKind::sphere_pair, 4, 5, 1.0),   // a rod's particles, another kind
      pair_row(ConstraintKind::sphere_pair, 3, 7, 1.01),  // another contact distance
      pair_row(ConstraintKind::sphere_pair, 9, 2, 0.8),   // held
      pair_row(ConstraintKind::sphere_pair, 3, 7, 1.0)};  // held
  // The candidates in one stretch, then in three (one of them empty), as the threads that
  // screened them leave them: the same marks by their place in the whole.
  const std::vector<double> gaps(candidates.size(), 0.0);
  const std::vector<Constraint> head(candidates.begin(), candidates.begin() + 4), none;
  const std::vector<Constraint> tail(candidates.begin() + 4, candidates.end());
  RowStretches whole, split;
  whole.assign(candidates, gaps);
  split.assign(head, gaps);
  split.add(none, gaps);
  split.add(tail, gaps);
  for (const RowStretches* stretches : {&whole, &split}) {
    std::vector<std::pair<std::uint64_t, std::int32_t>> scratch;
    std::vector<char> contained;
    mark_contained(rows, *stretches, scratch, contained);
    ASSERT_EQ(contained.size(), candidates.size());
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      EXPECT_EQ(contained[k] != 0, contains(rows, candidates[k])) << "candidate " << k;
    }
    EXPECT_EQ(contained, (std::vector<char>{1, 0, 1, 0, 0, 0, 0, 1, 1}));
    // No rows: nothing held, scratch reused.
    mark_contained({}, *stretches, scratch, contained);
    EXPECT_EQ(contained, std::vector<char>(candidates.size(), 0));
  }
}

}  // namespace
}  // namespace deli
