// The thermostats' random numbers: Philox4x32-10 against Random123's known-answer vectors
// (kat_vectors, the generator's reference), and the moments of the derived variates.
#include "thermostats/random_stream.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace deli {
namespace {

TEST(Philox, MatchesRandom123KnownAnswers) {
  EXPECT_EQ(philox4x32_10({0, 0, 0, 0}, {0, 0}),
            (PhiloxCounter{0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}));
  EXPECT_EQ(
      philox4x32_10({0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}, {0xffffffff, 0xffffffff}),
      (PhiloxCounter{0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}));
  EXPECT_EQ(
      philox4x32_10({0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}, {0xa4093822, 0x299f31d0}),
      (PhiloxCounter{0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}));
}

// Sample moments against the exact ones, within 5 standard errors of the estimates.
struct Moments {
  double mean = 0, variance = 0;
};
template <class Draw>
Moments moments(Draw draw, int n) {
  double sum = 0, sum2 = 0;
  for (int k = 0; k < n; ++k) {
    const double x = draw(k);
    sum += x;
    sum2 += x * x;
  }
  const double mean = sum / n;
  return {mean, sum2 / n - mean * mean};
}

TEST(RandomStream, NormalsHaveUnitVarianceAcrossStreams) {
  // One stream per counter, as the Langevin thermostat draws them (three per atom).
  const int n = 200000;
  const Moments m = moments(
      [](int k) {
        RandomStream s(42, {static_cast<std::uint32_t>(k / 3), 0, 7, 0});
        double x = 0;
        for (int j = 0; j <= k % 3; ++j) x = s.normal();
        return x;
      },
      n);
  EXPECT_NEAR(m.mean, 0.0, 5.0 / std::sqrt(n));
  EXPECT_NEAR(m.variance, 1.0, 5.0 * std::sqrt(2.0 / n));
}

TEST(RandomStream, GammaHasItsMeanAndVariance) {
  // Gamma(a, 1): mean a, variance a; a < 1 goes through the boost a + 1.
  for (double shape : {0.5, 1.0, 2.5, 149.5}) {
    const int n = 50000;
    RandomStream s(9, {1, 2, 3, 0});
    const Moments m = moments([&](int) { return s.gamma(shape); }, n);
    EXPECT_NEAR(m.mean, shape, 5.0 * std::sqrt(shape / n)) << "shape " << shape;
    // Var of the sample variance of a gamma: (mu4 - sigma^4) / n, mu4 = 3a^2 + 6a.
    EXPECT_NEAR(m.variance, shape, 5.0 * std::sqrt((2 * shape * shape + 6 * shape) / n))
        << "shape " << shape;
  }
}

TEST(RandomStream, SameCounterSameNumbersOtherSeedOthers) {
  RandomStream a(5, {1, 2, 3, 0}), b(5, {1, 2, 3, 0}), c(6, {1, 2, 3, 0});
  const double x = a.normal();
  EXPECT_EQ(x, b.normal());
  EXPECT_NE(x, c.normal());
}

}  // namespace
}  // namespace deli
