// The bounded-or-drifting check the paper and GVI tests use (support/energy_trend.hpp),
// on series whose answer is known by construction.
#include "support/energy_trend.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace deli::testing {
namespace {

std::vector<double> series(double drift_per_sample, double amplitude, double period,
                           std::size_t n = 10000) {
  std::vector<double> e(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k);
    e[k] = drift_per_sample * t + amplitude * std::sin(2 * M_PI * t / period);
  }
  return e;
}

// The old check (largest error of the second half over the first) gives exactly 2 for a
// linear drift, whatever its size, so "< 2" could not fail on one; the trend does.
TEST(EnergyTrend, PureLinearDriftIsAllTrend) {
  const EnergyTrend t = energy_trend(series(1e-6, 0.0, 1.0));
  EXPECT_NEAR(t.trend, 1e-6 * 9999, 1e-12);
  EXPECT_GT(t.ratio(), 1e3);
}

TEST(EnergyTrend, BoundedOscillationHasNoTrend) {
  // 100 periods: the fitted slope of a sine over whole periods is zero up to the end effect.
  const EnergyTrend t = energy_trend(series(0.0, 1e-3, 100.0));
  // The amplitude, and a little more at the ends where the small fitted slope adds (1 %).
  EXPECT_NEAR(t.fluctuation, 1e-3, 2e-5);
  EXPECT_LT(t.ratio(), 0.05);
}

// A drift under a larger oscillation: found once it carries the error further than the
// oscillation over the run (trend 2e-3 against an amplitude of 1e-3).
TEST(EnergyTrend, DriftUnderOscillationIsFound) {
  const EnergyTrend t = energy_trend(series(2e-7, 1e-3, 100.0));
  EXPECT_GT(t.ratio(), 1.5);
}

}  // namespace
}  // namespace deli::testing
