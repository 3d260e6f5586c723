// The thermostats' random numbers: Philox4x32-10 against Random123's known-answer vectors
// (kat_vectors, the generator's reference), and the moments of the derived variates.
#include "thermostats/random_stream.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "thermostats/normal_triples.hpp"
#include "thermostats/polar_log.hpp"

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

// The units in the last place between two positive finite doubles (their bit patterns'
// distance).
std::uint64_t ulps_apart(double a, double b) {
  std::int64_t ia, ib;
  std::memcpy(&ia, &a, sizeof a);
  std::memcpy(&ib, &b, sizeof b);
  if ((ia < 0) != (ib < 0)) return a == b ? 0 : ~std::uint64_t{0};
  return static_cast<std::uint64_t>(ia > ib ? ia - ib : ib - ia);
}

// polar_log against libm's log (a second implementation): within one unit in the last place
// on the polar method's s, uniform in (0, 1) and where its three forms change: near each power
// of two (f within 2^-20 of 0, where the first form takes over), near its two scaled ranges'
// edges (mantissas 1.38 and 1.42), and at exact powers of two (f = 0: k ln 2 alone).
TEST(PolarLog, WithinOneUlpOfLibmsLogOnTheUnitInterval) {
  std::mt19937_64 random(2026);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<double> s;
  for (int k = 0; k < 400000; ++k) s.push_back(uniform(random));
  for (int e = -60; e <= 0; ++e) {
    const double power = std::ldexp(1.0, e);
    for (int k = 1; k < 200; ++k) {
      const double step = power * std::ldexp(1.0, -20) * k / 100.0;
      if (e < 0) s.push_back(power + step);
      s.push_back(power - step / 2);
    }
    if (e < 0) s.push_back(power);
    for (const double mantissa : {1.38, 1.42, 1.3799, 1.4201}) {
      s.push_back(std::ldexp(mantissa, e - 1));
      s.push_back(std::nextafter(std::ldexp(mantissa, e - 1), 0.0));
    }
  }
  s.push_back(1.0);
  s.push_back(std::nextafter(1.0, 0.0));
  std::uint64_t worst = 0;
  double worst_at = 0.0;
  for (const double x : s) {
    ASSERT_GT(x, 0.0);
    ASSERT_LE(x, 1.0);
    const std::uint64_t apart = ulps_apart(polar_log(x), std::log(x));
    if (apart > worst) worst = apart, worst_at = x;
  }
  EXPECT_LE(worst, 1u) << "at s = " << worst_at;
  EXPECT_EQ(polar_log(1.0), 0.0);
  EXPECT_EQ(polar_log(0.5), -std::log(2.0));
}

// The Langevin thermostat's draws (normal_triples: eight streams at a time where the build
// has AVX-512, four where it has AVX2) are three RandomStream::normal() calls per stream, bit for
// bit: streams whose two accepted pairs lie in their first two Philox blocks, in the third, and
// those RandomStream draws itself (fewer than two of their first six pairs accepted) all occur.
// 4099 counters (a tail shorter than eight), ids and steps over their 32-bit halves, a last
// word near 2^32 - 1 (the next blocks' counters wrap), two seeds with both halves set.
TEST(RandomStream, NormalTriplesAreThreeNormalCallsBitForBit) {
  std::vector<PhiloxCounter> start(4099);
  for (std::size_t k = 0; k < start.size(); ++k) {
    const auto w = static_cast<std::uint32_t>(k);
    start[k] = {w * 2654435761u, w >> 3, 0x9e3779b9u * (w % 7),
                k % 97 == 0 ? 0xffffffffu - (w % 2) : w << 16};
  }
  for (const std::uint64_t seed : {std::uint64_t{7}, std::uint64_t{0x123456789abcdef0}}) {
    // Per stream, the accepted pairs (s < 1) among its first six: two in the first four
    // (the common case), two only with the fifth and sixth (the third block), or fewer.
    const PhiloxKey key{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)};
    std::size_t third_block = 0, fallback = 0;
    for (const PhiloxCounter& c : start) {
      int accepted_in_four = 0, accepted_in_six = 0;
      PhiloxCounter counter = c;
      for (int b = 0; b < 3; ++b, ++counter[3]) {
        const PhiloxCounter block = philox4x32_10(counter, key);
        for (int pair = 0; pair < 2; ++pair) {
          auto symmetric = [&](int word) {
            return (static_cast<double>(static_cast<std::int32_t>(block[word])) + 0.5) * 0x1.0p-31;
          };
          const double u = symmetric(2 * pair), v = symmetric(2 * pair + 1);
          const bool accepted = u * u + v * v < 1.0;
          accepted_in_six += accepted;
          accepted_in_four += accepted && b < 2;
        }
      }
      third_block += accepted_in_four < 2 && accepted_in_six >= 2;
      fallback += accepted_in_six < 2;
    }
    EXPECT_GT(third_block, 40u) << "seed " << seed;
    EXPECT_GT(fallback, 0u) << "seed " << seed;
    std::vector<Vec3> fast(start.size()), reference(start.size());
    normal_triples(seed, start.data(), start.size(), fast.data());
    normal_triples_by_stream(seed, start.data(), start.size(), reference.data());
    for (std::size_t k = 0; k < start.size(); ++k) {
      ASSERT_EQ(fast[k].x, reference[k].x) << "stream " << k;
      ASSERT_EQ(fast[k].y, reference[k].y) << "stream " << k;
      ASSERT_EQ(fast[k].z, reference[k].z) << "stream " << k;
    }
    // The reference is RandomStream's own three calls.
    RandomStream last(seed, start.back());
    EXPECT_EQ(reference.back().x, last.normal());
    EXPECT_EQ(reference.back().y, last.normal());
    EXPECT_EQ(reference.back().z, last.normal());
  }
  if (!normal_triples_vectorised()) GTEST_SKIP() << "no vector draws in this build";
}

}  // namespace
}  // namespace deli
