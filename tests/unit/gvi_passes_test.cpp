// GVI's per-particle passes (integrators/gvi_passes.hpp, built for the build machine's vector
// width) give, bit for bit, the numbers of the Vec3 expressions they replace in gvi.cpp, and
// the same maxima and counts as the per-particle loops: on ranges that start past 0 and cross
// the passes' blocks of 256, with signed zeros (a zero impulse adds +0), a NaN position (it
// counts as beyond the list, as NeighborList::keeps_valid has it) and unequal masses.
#include "integrators/gvi_passes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/vec3.hpp"

namespace deli {
namespace {

constexpr std::size_t kParticles = 700, kBegin = 3, kEnd = 611;
constexpr double kStep = 0.005;

struct State {
  std::vector<Vec3> x, v, f, p, half, impulse, built;
  std::vector<double> mass, reach2;
};

State random_state(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> mass(0.5, 3.0);
  auto vec = [&](double scale) { return Vec3{normal(rng), normal(rng), normal(rng)} * scale; };
  State s;
  for (std::size_t i = 0; i < kParticles; ++i) {
    s.x.push_back(vec(5.0));
    s.v.push_back(vec(1.0));
    s.f.push_back(vec(30.0));
    s.p.push_back(vec(1.0));
    s.half.push_back(vec(1.0));
    s.impulse.push_back(vec(0.01));
    s.built.push_back(s.x.back() + vec(0.08));
    s.mass.push_back(mass(rng));
    s.reach2.push_back(std::abs(normal(rng)) * 1e-4);
  }
  // Signed zeros: -0 + +0 is +0, which the passes must keep making.
  s.half[10] = Vec3{-0.0, -0.0, 1.0};
  s.impulse[10] = Vec3{-0.0, 0.0, -0.0};
  s.x[10] = Vec3{-0.0, -0.0, 1.0};
  s.f[11] = Vec3{-0.0, -0.0, -0.0};
  s.p[11] = Vec3{-0.0, 0.5, -0.0};
  s.half[11] = Vec3{-0.0, -0.0, 2.0};
  // A non-finite position: beyond every reach.
  s.x[400].y = std::numeric_limits<double>::quiet_NaN();
  return s;
}

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}
void expect_same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b, const char* what) {
  for (std::size_t i = kBegin; i < kEnd; ++i) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_TRUE(same_bits(a[i][c], b[i][c])) << what << ", particle " << i << ", axis " << c;
    }
  }
}
double* flat(std::vector<Vec3>& v) {
  return &v[0].x;
}
const double* flat(const std::vector<Vec3>& v) {
  return &v[0].x;
}
const double limit2 = 0.25 * 0.3 * 0.3;  // keeps_valid's for a skin of 0.3

// Gvi::start_step's loop before the passes.
TEST(GviPasses, StartIsTheVec3Loop) {
  const State s = random_state(1);
  std::vector<Vec3> q(kParticles), p(kParticles), predicted(kParticles);
  std::vector<Vec3> q_ref(kParticles), p_ref(kParticles), predicted_ref(kParticles);
  std::size_t beyond_ref = 0;
  for (std::size_t i = kBegin; i < kEnd; ++i) {
    q_ref[i] = s.x[i];
    p_ref[i] = s.v[i] * s.mass[i];
    const Vec3 d = (p_ref[i] + s.f[i] * (0.5 * kStep)) * (kStep / s.mass[i]);
    predicted_ref[i] = s.x[i] + d;
    beyond_ref += !(norm2(predicted_ref[i] - s.built[i]) <= limit2);
  }
  ASSERT_GT(beyond_ref, 0u);
  const std::size_t beyond =
      gvi_passes::start(kBegin, kEnd, kStep, flat(s.x), flat(s.v), s.mass.data(), flat(s.f),
                        flat(q), flat(p), flat(predicted), flat(s.built), limit2);
  EXPECT_EQ(beyond, beyond_ref);
  expect_same_bits(q, q_ref, "q");
  expect_same_bits(p, p_ref, "p");
  expect_same_bits(predicted, predicted_ref, "prediction");
  // Without the prediction stored nor the list tested: the same momenta, nothing counted.
  std::vector<Vec3> p_again(kParticles);
  EXPECT_EQ(gvi_passes::start(kBegin, kEnd, kStep, flat(s.x), flat(s.v), s.mass.data(), flat(s.f),
                              flat(q), flat(p_again), nullptr, nullptr, limit2),
            0u);
  expect_same_bits(p_again, p_ref, "p without the prediction");
}

// Gvi::solve_held_positions' half kick and free step, and update_momenta's kick and
// velocities.
TEST(GviPasses, KicksAndVelocitiesAreTheVec3Loops) {
  const State s = random_state(2);
  std::vector<Vec3> half(kParticles), free(kParticles), half_ref(kParticles), free_ref(kParticles);
  std::vector<Vec3> p(kParticles), p_ref(kParticles), p_zero(kParticles), p_zero_ref(kParticles);
  std::vector<Vec3> v(kParticles), v_ref(kParticles);
  for (std::size_t i = kBegin; i < kEnd; ++i) {
    half_ref[i] = s.p[i] + s.f[i] * (0.5 * kStep);
    free_ref[i] = half_ref[i] * (kStep / s.mass[i]);
    Vec3 momentum = s.half[i] + s.impulse[i];
    momentum += s.f[i] * (0.5 * kStep);
    p_ref[i] = momentum;
    Vec3 unheld = s.half[i] + Vec3{};  // no row held: a zero impulse
    unheld += s.f[i] * (0.5 * kStep);
    p_zero_ref[i] = unheld;
    v_ref[i] = s.p[i] * (1.0 / s.mass[i]);
  }
  gvi_passes::half_kick(kBegin, kEnd, kStep, flat(s.p), flat(s.f), s.mass.data(), flat(half),
                        flat(free));
  gvi_passes::kick(kBegin, kEnd, kStep, flat(s.half), flat(s.impulse), flat(s.f), flat(p));
  gvi_passes::kick(kBegin, kEnd, kStep, flat(s.half), nullptr, flat(s.f), flat(p_zero));
  gvi_passes::velocities(kBegin, kEnd, flat(s.p), s.mass.data(), flat(v));
  expect_same_bits(half, half_ref, "half kick");
  expect_same_bits(free, free_ref, "free step");
  expect_same_bits(p, p_ref, "kick");
  expect_same_bits(p_zero, p_zero_ref, "kick without impulses");
  expect_same_bits(v, v_ref, "velocities");
}

// Gvi::displaced's loop: the end positions, the largest squared displacement (std::max from
// a start), and the counts beyond the reaches and the list.
TEST(GviPasses, EndPositionsAreTheVec3Loop) {
  State s = random_state(3);
  s.half[400].x = std::numeric_limits<double>::quiet_NaN();  // a NaN end position
  for (const bool with_impulse : {true, false}) {
    SCOPED_TRACE(with_impulse ? "impulses" : "no impulse");
    const double start = 1e-9;
    std::vector<Vec3> x(kParticles), x_ref(kParticles);
    double largest_ref = start;
    std::size_t reach_ref = 0, list_ref = 0;
    for (std::size_t i = kBegin; i < kEnd; ++i) {
      const Vec3 j = with_impulse ? s.impulse[i] : Vec3{};
      x_ref[i] = s.x[i] + (s.half[i] + j) * (kStep / s.mass[i]);
      const double moved2 = norm2(x_ref[i] - s.x[i]);
      largest_ref = std::max(largest_ref, moved2);
      reach_ref += !(moved2 <= s.reach2[i]);
      list_ref += !(norm2(x_ref[i] - s.built[i]) <= limit2);
    }
    ASSERT_GT(reach_ref, 0u);
    ASSERT_LT(reach_ref, kEnd - kBegin);
    ASSERT_GT(list_ref, 0u);
    const gvi_passes::EndPositions ends = gvi_passes::end_positions(
        kBegin, kEnd, kStep, flat(s.x), flat(s.half), with_impulse ? flat(s.impulse) : nullptr,
        s.mass.data(), flat(x), start, s.reach2.data(), flat(s.built), limit2);
    expect_same_bits(x, x_ref, "end positions");
    EXPECT_TRUE(same_bits(ends.largest, largest_ref));
    EXPECT_EQ(ends.beyond_reach, reach_ref);
    EXPECT_EQ(ends.beyond_list, list_ref);
    // Without reaches nor a list: nothing counted, the same maximum.
    const gvi_passes::EndPositions bare = gvi_passes::end_positions(
        kBegin, kEnd, kStep, flat(s.x), flat(s.half), with_impulse ? flat(s.impulse) : nullptr,
        s.mass.data(), flat(x), start, nullptr, nullptr, limit2);
    EXPECT_TRUE(same_bits(bare.largest, largest_ref));
    EXPECT_EQ(bare.beyond_reach + bare.beyond_list, 0u);
  }
}

}  // namespace
}  // namespace deli
