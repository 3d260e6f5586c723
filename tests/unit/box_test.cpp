// Box::minimum_image at the edges of the double range. Expected values: the nearest periodic
// image by definition (|d| <= period / 2 along a periodic axis, d unchanged along an open
// one), and IEEE propagation for a non-finite separation, which the engine's finiteness
// checks then report. The integer conversion it rounds with is undefined for NaN and for
// magnitudes from 2^63 up (the sanitizer pass's float-cast-overflow check stops on it).
#include "system/box.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace deli {
namespace {

TEST(Box, MinimumImageOfAHugeSeparationIsWithinHalfAPeriod) {
  const Box box({0, 0, 0}, {1, 2, 4}, {true, true, true});
  // 1e20 and 2^53 + 2 are whole multiples of the periods 1 and 2 in double: their image is 0.
  const Vec3 d = box.minimum_image({1e20, 0x1p53 + 2, -3e19});
  EXPECT_EQ(d.x, 0.0);
  EXPECT_EQ(d.y, 0.0);
  EXPECT_LE(std::abs(d.z), 2.0);
  // Below 2^52 the rounding is the integer conversion's, half away from zero.
  EXPECT_EQ(Box::round_to_integer(2.5), 3.0);
  EXPECT_EQ(Box::round_to_integer(-2.5), -3.0);
  EXPECT_EQ(Box::round_to_integer(0x1p52 - 0.5), 0x1p52);
  EXPECT_EQ(Box::round_to_integer(0x1p52 + 1), 0x1p52 + 1);
}

TEST(Box, MinimumImageOfANonFiniteSeparationStaysNonFinite) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Box periodic({0, 0, 0}, {3, 3, 3}, {true, true, true});
  const Box open({0, 0, 0}, {3, 3, 3}, {false, false, false});
  for (const Box& box : {periodic, open}) {
    const Vec3 d = box.minimum_image({nan, inf, -inf});
    EXPECT_TRUE(std::isnan(d.x));
    EXPECT_FALSE(std::isfinite(d.y));
    EXPECT_FALSE(std::isfinite(d.z));
    // The finite axes of a separation with a NaN elsewhere are imaged as usual.
    const Vec3 mixed = box.minimum_image({nan, 2.0, -0.5});
    EXPECT_EQ(mixed.y, box.periodic(1) ? -1.0 : 2.0);
    EXPECT_EQ(mixed.z, -0.5);
  }
}

}  // namespace
}  // namespace deli
