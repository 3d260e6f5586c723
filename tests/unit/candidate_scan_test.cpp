// The list build's candidate scan (vectorised where the CPU has AVX-512) finds exactly the
// candidates a plain loop finds, in slot order, with the run's code: on runs of every length
// around the vector width, at offsets that leave partial vectors, with candidates exactly at
// the reach (not within: the test is strict), NaN positions (never within) and hits appended
// after earlier ones.
#include "neighbor/candidate_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace deli {
namespace {

struct Hits {
  std::vector<std::int32_t> slot;
  std::vector<std::uint8_t> code;
};

// The reference: the definition in candidate_scan.hpp, one candidate at a time.
void reference_scan(const std::vector<double>& x, const std::vector<double>& y,
                    const std::vector<double>& z, std::size_t first, std::size_t last,
                    const double o[3], double within2, std::uint8_t code, Hits& out) {
  for (std::size_t m = first; m < last; ++m) {
    const double dx = x[m] - o[0], dy = y[m] - o[1], dz = z[m] - o[2];
    if (dx * dx + dy * dy + dz * dz < within2) {
      out.slot.push_back(static_cast<std::int32_t>(m));
      out.code.push_back(code);
    }
  }
}

TEST(CandidateScan, SameHitsInSameOrderAsOneAtATime) {
  constexpr std::size_t n = 64;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<double> x(n), y(n), z(n);
  for (std::size_t m = 0; m < n; ++m) x[m] = u(rng), y[m] = u(rng), z[m] = u(rng);
  const double origin[3] = {0.25, -0.125, 0.5};
  const double within2 = 1.0;
  // On the reach exactly (dx = 1: r2 == within2, not within), just inside it, and NaN.
  x[5] = origin[0] + 1.0, y[5] = origin[1], z[5] = origin[2];
  x[6] = origin[0] + std::nextafter(1.0, 0.0), y[6] = origin[1], z[6] = origin[2];
  x[13] = std::numeric_limits<double>::quiet_NaN();
  y[21] = std::numeric_limits<double>::infinity();

  std::size_t runs = 0, found = 0;
  for (std::size_t first = 0; first < 12; ++first) {
    for (std::size_t length = 0; length <= 40; ++length) {
      const std::size_t last = first + length;
      // Earlier hits already in the output: the run appends after them.
      Hits expected{{-1, -2, -3}, {9, 9, 9}};
      reference_scan(x, y, z, first, last, origin, within2, 4, expected);
      std::vector<std::int32_t> slot(3 + length + kScanSlack, -7);
      std::vector<std::uint8_t> code(3 + length + kScanSlack, 99);
      for (int k = 0; k < 3; ++k) slot[k] = expected.slot[k], code[k] = 9;
      const std::size_t hits =
          scan_candidates(x.data(), y.data(), z.data(), first, last, origin[0], origin[1],
                          origin[2], within2, 4, slot.data(), code.data(), 3);
      ASSERT_EQ(hits, expected.slot.size()) << "run [" << first << ", " << last << ")";
      for (std::size_t h = 0; h < hits; ++h) {
        ASSERT_EQ(slot[h], expected.slot[h]) << "run [" << first << ", " << last << ") hit " << h;
        ASSERT_EQ(code[h], expected.code[h]) << "run [" << first << ", " << last << ") hit " << h;
      }
      ++runs;
      found += hits - 3;
    }
  }
  // The cases exercised: hits found, and the edge candidates scanned in many runs.
  EXPECT_EQ(runs, 12u * 41u);
  EXPECT_GT(found, 1000u);
}

}  // namespace
}  // namespace deli
