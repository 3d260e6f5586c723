// The list build's candidate scan (vectorised where the CPU has AVX-512 or AVX2) finds exactly the
// candidates a plain loop finds, in slot order, with the run's code: on runs of every length
// around the vector width, at offsets that leave partial vectors, with candidates exactly at
// the reach (not within: the test is strict), NaN positions (never within) and hits appended
// after earlier ones. A particle's whole stencil scanned in one call (scan_stencil) finds what
// the reference finds run after run, each run against the origin less its image shift. The
// hits made list entries (keep_hits) are its definition's, one hit at a time.
#include "neighbor/candidate_scan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
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

TEST(CandidateScan, StencilScanFindsEveryRunsHitsInRunOrder) {
  // 12 cells of 0 to 19 candidates (runs of 0 to 38 candidates: empty runs, partial vectors
  // and runs past the two vectors scan_stencil always tests), positions around the origin.
  constexpr int cells = 12;
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> count(0, 19);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<std::size_t> cell_start(cells + 1, 0);
  for (int c = 0; c < cells; ++c) cell_start[c + 1] = cell_start[c] + count(rng);
  const std::size_t n = cell_start.back();
  std::vector<double> x(n), y(n), z(n);
  for (std::size_t m = 0; m < n; ++m) x[m] = u(rng), y[m] = u(rng), z[m] = u(rng);
  double shifts[27][3];
  for (int code = 0; code < 27; ++code) {
    shifts[code][0] = 0.25 * (code % 3 - 1);
    shifts[code][1] = 0.5 * ((code / 3) % 3 - 1);
    shifts[code][2] = -0.375 * (code / 9 - 1);
  }
  // Runs of one or two cells, with several image codes, the last one empty.
  const std::vector<std::int32_t> run_cells = {2, 4, 5, 7, 9, 0, 11, 3};
  const std::vector<std::int32_t> run_ends = {4, 5, 7, 8, 11, 1, 12, 3};
  const std::vector<std::uint8_t> run_codes = {13, 14, 0, 26, 13, 5, 22, 13};
  const StencilRuns runs{cell_start.data(), run_cells.data(), run_ends.data(), run_codes.data(),
                         shifts};
  // The case holds a run past two vectors.
  std::size_t longest = 0;
  for (std::size_t s = 0; s < run_cells.size(); ++s) {
    longest = std::max(longest, cell_start[run_ends[s]] - cell_start[run_cells[s]]);
  }
  EXPECT_GT(longest, 16u);
  const double xi[3] = {0.125, -0.25, 0.0625};
  const double within2 = 1.21;
  // Candidates of the home run on the reach and a few units in the last place either side
  // of it: the first test in floats leaves them unsure, and the doubles decide.
  for (std::size_t m = 0; m < 6 && m < cell_start[2]; ++m) {
    const double r = std::sqrt(within2) + (static_cast<double>(m) - 2.5) * 1e-16;
    x[m] = xi[0] + r * 0.6, y[m] = xi[1] - r * 0.8, z[m] = xi[2];
  }
  // The same positions in floats, and the bounds of their first test.
  std::vector<float> xf(n), yf(n), zf(n);
  double largest = 0.0;
  for (std::size_t m = 0; m < n; ++m) {
    xf[m] = static_cast<float>(x[m]), yf[m] = static_cast<float>(y[m]);
    zf[m] = static_cast<float>(z[m]);
    largest = std::max({largest, std::abs(x[m]), std::abs(y[m]), std::abs(z[m])});
  }
  FloatPositions in_float{xf.data(), yf.data(), zf.data(), 0.0f, 0.0f};
  ASSERT_TRUE(float_bounds(largest + 1.0, within2, in_float.within2_below, in_float.within2_above));
  std::size_t unsure = 0;
  for (std::size_t m = 0; m < cell_start[2]; ++m) {
    const float dx = xf[m] - static_cast<float>(xi[0]), dy = yf[m] - static_cast<float>(xi[1]),
                dz = zf[m] - static_cast<float>(xi[2]);
    const float r2 = dx * dx + dy * dy + dz * dz;
    unsure += r2 >= in_float.within2_below && r2 < in_float.within2_above;
  }
  EXPECT_GE(unsure, 4u);
  for (const FloatPositions* floats :
       {static_cast<const FloatPositions*>(nullptr), static_cast<const FloatPositions*>(&in_float)})
    for (std::size_t home_first = 0; home_first <= cell_start[2]; ++home_first) {
      for (std::size_t begin = 0; begin <= run_cells.size(); begin += 3) {
        const std::size_t home_last = cell_start[2];
        Hits expected;
        auto reference_run = [&](std::size_t first, std::size_t last, std::uint8_t code) {
          const double o[3] = {xi[0] - shifts[code][0], xi[1] - shifts[code][1],
                               xi[2] - shifts[code][2]};
          reference_scan(x, y, z, first, last, o, within2, code, expected);
        };
        reference_run(home_first, home_last, 13);
        for (std::size_t s = begin; s < run_cells.size(); ++s) {
          reference_run(cell_start[run_cells[s]], cell_start[run_ends[s]], run_codes[s]);
        }
        std::vector<std::int32_t> slot(n + kScanSlack, -7);
        std::vector<std::uint8_t> code(n + kScanSlack, 99);
        const std::size_t hits = scan_stencil(x.data(), y.data(), z.data(), runs, home_first,
                                              home_last, 13, begin, run_cells.size(), xi[0], xi[1],
                                              xi[2], within2, slot.data(), code.data(), floats);
        ASSERT_EQ(hits, expected.slot.size())
            << "home from " << home_first << ", runs from " << begin << ", floats " << !!floats;
        for (std::size_t h = 0; h < hits; ++h) {
          ASSERT_EQ(slot[h], expected.slot[h]) << "hit " << h;
          ASSERT_EQ(code[h], expected.code[h]) << "hit " << h;
        }
        if (home_first == 0 && begin == 0) {
          EXPECT_GE(hits, 10u);  // the case has hits
        }
      }
    }
}

// float_bounds against a second computation: candidates near the reach (over the unsure band
// and as far again either side), their coordinates and origins up to `largest` in magnitude (1, the
// LJ 32000 box's 67, 1e4), each r^2 computed as the scan computes it in floats and in doubles.
// Below the lower bound in floats must mean within in doubles, at or above the upper one beyond;
// both decisions, and the unsure band between, occur.
TEST(CandidateScan, FloatBoundsHoldTheDoublesDecision) {
  std::mt19937_64 rng(17);
  const double within2 = 7.84;
  for (const double largest : {1.0, 67.0, 1e4}) {
    float below = 0.0f, above = 0.0f;
    ASSERT_TRUE(float_bounds(largest, within2, below, above));
    EXPECT_LT(below, within2);
    EXPECT_GT(above, within2);
    // Separations spread over the unsure band and as far again either side of it.
    const double spread = (above - below) / within2;
    std::uniform_real_distribution<double> place(-largest + 3.0, largest - 3.0), unit(-1.0, 1.0),
        nudge(-spread, spread);
    std::size_t inside = 0, outside = 0, unsure = 0;
    for (int sample = 0; sample < 200000; ++sample) {
      const double o[3] = {place(rng), place(rng), place(rng)};
      double d[3] = {unit(rng), unit(rng), unit(rng)};
      const double scale = std::sqrt(within2) * (1.0 + nudge(rng)) /
                           std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const double c[3] = {o[0] + d[0] * scale, o[1] + d[1] * scale, o[2] + d[2] * scale};
      const double ex = c[0] - o[0], ey = c[1] - o[1], ez = c[2] - o[2];
      const double r2 = ex * ex + ey * ey + ez * ez;
      const float fx = static_cast<float>(c[0]) - static_cast<float>(o[0]);
      const float fy = static_cast<float>(c[1]) - static_cast<float>(o[1]);
      const float fz = static_cast<float>(c[2]) - static_cast<float>(o[2]);
      const float r2f = fx * fx + fy * fy + fz * fz;
      if (r2f < below) {
        ++inside;
        ASSERT_LT(r2, within2) << "largest " << largest << ", r2 in floats " << r2f;
      } else if (r2f >= above) {
        ++outside;
        ASSERT_GE(r2, within2) << "largest " << largest << ", r2 in floats " << r2f;
      } else {
        ++unsure;
      }
    }
    EXPECT_GT(inside, 1000u) << largest;
    EXPECT_GT(outside, 1000u) << largest;
    EXPECT_GT(unsure, 0u) << largest;
  }
  // Coordinates floats cannot hold: no bounds (the scan tests in doubles).
  float below = 0.0f, above = 0.0f;
  EXPECT_FALSE(float_bounds(1e31, within2, below, above));
  EXPECT_FALSE(float_bounds(std::numeric_limits<double>::infinity(), within2, below, above));
}

// keep_hits against its definition (candidate_scan.hpp), one hit at a time: hit counts of
// every remainder modulo 16 up to 50, particles' excluded partners from none to past
// kVectorExcluded (those take the one-by-one path), some listed among the hits, and moved
// keys that differ from the particle's for some hits (those listed to recode, in order); the
// kept hits listed as particles and as slots; without moved keys (all the particle's), none
// recoded.
TEST(CandidateScan, KeptHitsAreTheDefinitionsInOrder) {
  constexpr std::size_t slots = 300;
  std::mt19937_64 rng(31);
  std::vector<std::int32_t> member(slots), moved_key(slots);
  for (std::size_t m = 0; m < slots; ++m) member[m] = static_cast<std::int32_t>(m);
  std::shuffle(member.begin(), member.end(), rng);
  for (std::size_t m = 0; m < slots; ++m) moved_key[m] = rng() % 5 == 0 ? 3 : 0;
  std::size_t recoded_total = 0, dropped_total = 0;
  for (const bool keyed : {true, false})
    for (const bool as_slots : {false, true})
      for (std::size_t hits = 0; hits <= 50; ++hits) {
        for (std::size_t excluded_count = 0; excluded_count <= kVectorExcluded + 2;
             ++excluded_count) {
          std::vector<std::int32_t> hit_slot(hits + kScanSlack), excluded(excluded_count);
          std::vector<std::uint8_t> hit_code(hits + kScanSlack);
          for (std::size_t h = 0; h < hits; ++h) {
            hit_slot[h] = static_cast<std::int32_t>(rng() % slots);
            hit_code[h] = static_cast<std::uint8_t>(rng() % 27);
          }
          // Half the excluded partners among the hits, half elsewhere.
          for (std::size_t e = 0; e < excluded_count; ++e) {
            excluded[e] = e % 2 == 0 && hits > 0 ? member[hit_slot[rng() % hits]]
                                                 : static_cast<std::int32_t>(rng() % slots);
          }
          const std::int32_t key = 0;
          std::vector<std::int32_t> j(hits + kScanSlack);
          std::vector<std::uint8_t> code(hits + kScanSlack);
          std::vector<std::uint32_t> recode_kept(hits + 1), recode_hit(hits + 1);
          std::size_t recode = 0;
          const std::size_t kept =
              keep_hits(member.data(), keyed ? moved_key.data() : nullptr, key, hit_slot.data(),
                        hit_code.data(), hits, excluded.data(), excluded_count, j.data(),
                        code.data(), recode_kept.data(), recode_hit.data(), &recode, as_slots);
          std::vector<std::int32_t> want_j;
          std::vector<std::uint8_t> want_code;
          std::vector<std::uint32_t> want_kept, want_hit;
          for (std::size_t h = 0; h < hits; ++h) {
            const std::int32_t p = member[hit_slot[h]];
            if (std::find(excluded.begin(), excluded.end(), p) != excluded.end()) continue;
            if (keyed && moved_key[hit_slot[h]] != key) {
              want_kept.push_back(static_cast<std::uint32_t>(want_j.size()));
              want_hit.push_back(static_cast<std::uint32_t>(h));
            }
            want_j.push_back(as_slots ? hit_slot[h] : p);
            want_code.push_back(hit_code[h]);
          }
          ASSERT_EQ(kept, want_j.size())
              << hits << " hits, " << excluded_count << " excluded, as slots " << as_slots;
          EXPECT_TRUE(std::equal(want_j.begin(), want_j.end(), j.begin()));
          EXPECT_TRUE(std::equal(want_code.begin(), want_code.end(), code.begin()));
          ASSERT_EQ(recode, want_kept.size());
          EXPECT_TRUE(std::equal(want_kept.begin(), want_kept.end(), recode_kept.begin()));
          EXPECT_TRUE(std::equal(want_hit.begin(), want_hit.end(), recode_hit.begin()));
          recoded_total += recode;
          dropped_total += hits - kept;
        }
      }
  EXPECT_GT(recoded_total, 100u);
  EXPECT_GT(dropped_total, 100u);
}

}  // namespace
}  // namespace deli
