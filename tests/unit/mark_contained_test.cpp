// mark_contained (constrained_integrator.hpp) against its definition, contains() per
// candidate: rows that share particles (two walls of one particle, a pair and a rod on the
// same two particles, a pair listed as (j, i)) are told apart by the whole row.
#include <gtest/gtest.h>

#include "integrators/constrained_integrator.hpp"

namespace deli {
namespace {

Constraint pair(ConstraintKind kind, int i, int j, double length) {
  Constraint c{kind};
  c.i = i;
  c.j = j;
  c.length = length;
  return c;
}

Constraint plane(int i, Vec3 point, Vec3 normal) {
  Constraint c{ConstraintKind::plane};
  c.i = i;
  c.point = point;
  c.normal = normal;
  return c;
}

TEST(MarkContained, AgreesWithContainsRowByRow) {
  const std::vector<Constraint> rows = {
      pair(ConstraintKind::sphere_pair, 3, 7, 1.0), plane(2, {0, 0, 0}, {0, 0, 1}),
      pair(ConstraintKind::sphere_pair, 0, 1, 1.0), plane(2, {0, 0, 5}, {0, 0, -1}),
      pair(ConstraintKind::rod, 4, 5, 1.0),         pair(ConstraintKind::sphere_pair, 9, 2, 0.8)};
  const std::vector<Constraint> candidates = {
      pair(ConstraintKind::sphere_pair, 0, 1, 1.0),   // held
      pair(ConstraintKind::sphere_pair, 1, 0, 1.0),   // the same particles the other way
      plane(2, {0, 0, 5}, {0, 0, -1}),                // the second of particle 2's walls
      plane(2, {0, 0, 5}, {0, 0, 1}),                 // another normal
      plane(3, {0, 0, 0}, {0, 0, 1}),                 // another particle
      pair(ConstraintKind::sphere_pair, 4, 5, 1.0),   // a rod's particles, another kind
      pair(ConstraintKind::sphere_pair, 3, 7, 1.01),  // another contact distance
      pair(ConstraintKind::sphere_pair, 9, 2, 0.8),   // held
      pair(ConstraintKind::sphere_pair, 3, 7, 1.0)};  // held
  std::vector<std::pair<std::uint64_t, std::int32_t>> scratch;
  std::vector<char> contained;
  mark_contained(rows, candidates, scratch, contained);
  ASSERT_EQ(contained.size(), candidates.size());
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    EXPECT_EQ(contained[k] != 0, contains(rows, candidates[k])) << "candidate " << k;
  }
  EXPECT_EQ(contained, (std::vector<char>{1, 0, 1, 0, 0, 0, 0, 1, 1}));
  // No rows: nothing held, scratch reused.
  mark_contained({}, candidates, scratch, contained);
  EXPECT_EQ(contained, std::vector<char>(candidates.size(), 0));
}

}  // namespace
}  // namespace deli
