// The gap-only evaluations the candidate scans use agree with evaluate(): gap_of gives its
// gap bit for bit, and gap_unless_beyond gives it too unless the gap exceeds the limit (then
// +infinity), so comparisons with the limit and running minima come out the same. Pairs
// at separations straddling each limit to within a few roundings, across a periodic face.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "constraints/constraint.hpp"

namespace deli {
namespace {

TEST(ConstraintGap, GapOnlyScansAgreeWithEvaluate) {
  const Box box({0, 0, 0}, {6, 6, 6}, {true, true, true});
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> ulps(-4, 4);
  for (ConstraintKind kind : {ConstraintKind::sphere_pair, ConstraintKind::rod}) {
    for (double limit : {0.0, 1e-10, -1e-10, 0.09, -0.3, -0.9}) {
      for (int trial = 0; trial < 2000; ++trial) {
        Constraint c;
        c.kind = kind;
        c.i = 0, c.j = 1, c.length = 1.0;
        Vec3 u{normal(rng), normal(rng), normal(rng)};
        u = u * (1.0 / norm(u));
        // Half the pairs within a few roundings of the limit, half anywhere near contact.
        double r = c.length + limit;
        if (trial % 2) r += 0.5 * normal(rng);
        for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) {
          r = std::nextafter(r, k > 0 ? 10.0 : 0.0);
        }
        const std::vector<Vec3> x = {{5.9, 0.2, 3.0}, Vec3{5.9, 0.2, 3.0} + u * std::abs(r)};
        const double exact = evaluate(c, x.data(), box).gap;
        EXPECT_EQ(gap_of(c, x.data(), box), exact);
        const double screened = gap_unless_beyond(c, x.data(), box, limit);
        if (std::isinf(screened)) {
          EXPECT_GT(exact, limit);
        } else {
          EXPECT_EQ(screened, exact);
        }
        EXPECT_EQ(screened <= limit, exact <= limit);
        EXPECT_EQ(screened < limit, exact < limit);
      }
    }
  }
}

}  // namespace
}  // namespace deli
