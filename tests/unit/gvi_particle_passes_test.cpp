// GVI's passes over the particles (in vectors of eight particles where the CPU has them) make
// bit for bit the numbers of their definitions in gvi_particle_passes.hpp written as loops
// over Vec3, the form Gvi's passes had: on ranges of every length around the block of eight,
// at offsets that leave partial blocks, with a NaN, an infinity and negative zeros among the
// numbers, particles exactly at the list's and the reach's limits (inside: the tests are <=)
// and just beyond, and with and without the optional inputs and outputs.
#include "integrators/gvi_particle_passes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "core/vec3.hpp"

namespace deli {
namespace {

constexpr std::size_t kPassParticles = 40;

std::vector<Vec3> random_triples(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<Vec3> v(kPassParticles);
  for (Vec3& a : v) a = {u(rng), u(rng), u(rng)};
  return v;
}

double* pass_numbers(std::vector<Vec3>& v) {
  return reinterpret_cast<double*>(v.data());
}
const double* pass_numbers(const std::vector<Vec3>& v) {
  return reinterpret_cast<const double*>(v.data());
}

// Bit for bit (a NaN equals a NaN of the same bits; -0 differs from +0).
void expect_same_triples(const std::vector<Vec3>& expected, const std::vector<Vec3>& actual,
                         const char* what, std::size_t begin, std::size_t end) {
  for (std::size_t i = 0; i < expected.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(std::bit_cast<std::uint64_t>(expected[i][a]),
                std::bit_cast<std::uint64_t>(actual[i][a]))
          << what << " particle " << i << " axis " << a << " of range [" << begin << ", " << end
          << "): " << expected[i][a] << " against " << actual[i][a];
    }
  }
}

struct PassInputs {
  std::vector<Vec3> position, velocity, force, at_build, half, impulse;
  std::vector<double> mass, reach;
};

// Random particles with the edge cases: a NaN velocity, an infinite force, negative zeros
// (a momentum of -0 kicked by a force of -0 stays -0 up to the impulse), particles at the
// limits exactly and just beyond.
PassInputs edge_inputs(double list_limit2) {
  std::mt19937_64 rng(11);
  PassInputs s;
  s.position = random_triples(rng, 5.0);
  s.velocity = random_triples(rng, 2.0);
  s.force = random_triples(rng, 50.0);
  s.half = random_triples(rng, 2.0);
  s.impulse = random_triples(rng, 0.1);
  s.at_build = s.position;
  std::uniform_real_distribution<double> small(-0.05, 0.05), masses(0.5, 3.0);
  for (Vec3& a : s.at_build) a += Vec3{small(rng), small(rng), small(rng)};
  for (std::size_t i = 0; i < kPassParticles; ++i) s.mass.push_back(masses(rng));
  s.velocity[3].y = std::numeric_limits<double>::quiet_NaN();
  s.force[12].z = std::numeric_limits<double>::infinity();
  s.half[12].x = std::numeric_limits<double>::quiet_NaN();
  s.velocity[9] = {-0.0, -0.0, -0.0};
  s.force[9] = {-0.0, -0.0, -0.0};
  s.half[9] = {-0.0, -0.0, -0.0};
  s.impulse[9] = {-0.0, 0.0, -0.0};
  // At rest without force: the predicted and end positions are the start; placed exactly at
  // the list's limit from the build position (1 on x, the limit's square 1), and one ulp out.
  for (std::size_t i : {17u, 18u, 25u}) {
    s.velocity[i] = s.force[i] = s.half[i] = s.impulse[i] = Vec3{};
  }
  // (Numbers whose differences are exact.)
  const double limit = std::sqrt(list_limit2);
  s.position[17] = s.position[18] = s.position[25] = Vec3{2.0, 0.5, -1.5};
  s.at_build[17] = s.position[17] - Vec3{limit, 0.0, 0.0};
  s.at_build[18] = s.position[18] - Vec3{std::nextafter(limit, 2.0), 0.0, 0.0};
  s.at_build[25] = s.position[25];
  // A start position of -0: moved by +0 (a missing impulse added to -0) it is +0.
  s.position[9] = Vec3{-0.0, -0.0, -0.0};
  std::uniform_real_distribution<double> reach(1e-6, 1e-3);
  for (std::size_t i = 0; i < kPassParticles; ++i) s.reach.push_back(reach(rng));
  return s;
}

// step_start's inputs from the particles (its outputs left null).
gvi_passes::StepStart step_start_inputs(const PassInputs& s, double h) {
  gvi_passes::StepStart pass;
  pass.h = h;
  pass.position = pass_numbers(s.position);
  pass.velocity = pass_numbers(s.velocity);
  pass.mass = s.mass.data();
  pass.force = pass_numbers(s.force);
  return pass;
}

TEST(GviParticlePasses, StepStartMakesTheVec3LoopsNumbers) {
  const double h = 0.005;
  const double list_limit2 = 1.0;
  const PassInputs s = edge_inputs(list_limit2);
  std::size_t ranges = 0, counted = 0;
  double largest_seen = 0.0;
  for (bool listed : {true, false}) {
    for (bool kick : {true, false}) {
      for (std::size_t begin = 0; begin < 9; ++begin) {
        for (std::size_t end = begin; end <= kPassParticles; ++end) {
          // The definition, as start_step wrote it.
          std::vector<Vec3> q(kPassParticles), p(kPassParticles), half(kPassParticles),
              free(kPassParticles), impulse(kPassParticles, Vec3{7, 7, 7}),
              predicted(kPassParticles), p_start(kPassParticles, Vec3{5, 5, 5});
          std::vector<Vec3> q2 = q, p2 = p, half2 = half, free2 = free, impulse2 = impulse,
                            predicted2 = predicted, p_start2 = p_start;
          std::vector<double> displacement2(kPassParticles, 9.0),
              displacement2_made = displacement2;
          std::size_t expected = 0;
          double largest2 = 0.0;  // as collect_by_particle_reach's ordered_max takes it
          for (std::size_t i = begin; i < end; ++i) {
            q[i] = s.position[i];
            const Vec3 momentum = s.velocity[i] * s.mass[i];
            p[i] = momentum;
            p_start[i] = momentum;
            half[i] = momentum + s.force[i] * (0.5 * h);
            free[i] = half[i] * (h / s.mass[i]);
            impulse[i] = Vec3{};
            predicted[i] = s.position[i] + free[i];
            if (listed) expected += !(norm2(predicted[i] - s.at_build[i]) <= list_limit2);
            displacement2[i] = norm2(predicted[i] - q[i]);
            largest2 = std::max(largest2, displacement2[i]);
          }
          gvi_passes::StepStart pass = step_start_inputs(s, h);
          pass.at_build = listed ? pass_numbers(s.at_build) : nullptr;
          pass.list_limit2 = list_limit2;
          pass.q = pass_numbers(q2);
          pass.p = kick ? nullptr : pass_numbers(p2);
          pass.p_start = kick ? nullptr : pass_numbers(p_start2);
          pass.half = kick ? pass_numbers(half2) : nullptr;
          pass.free = kick ? pass_numbers(free2) : nullptr;
          pass.impulse = kick ? pass_numbers(impulse2) : nullptr;
          pass.predicted = kick ? nullptr : pass_numbers(predicted2);
          pass.displacement2 = displacement2_made.data();
          const gvi_passes::StepStartTally tally = gvi_passes::step_start(pass, begin, end);
          ASSERT_EQ(tally.beyond_list, expected) << "[" << begin << ", " << end << ")";
          counted += expected;
          expect_same_triples(q, q2, "q", begin, end);
          if (kick) {
            expect_same_triples(half, half2, "half", begin, end);
            expect_same_triples(free, free2, "free", begin, end);
            expect_same_triples(impulse, impulse2, "impulse", begin, end);
            // Without the prediction, no displacement is written and none is the largest.
            EXPECT_EQ(displacement2_made, std::vector<double>(kPassParticles, 9.0));
            EXPECT_EQ(tally.largest2, 0.0);
          } else {
            expect_same_triples(p, p2, "p", begin, end);
            expect_same_triples(p_start, p_start2, "p_start", begin, end);
            expect_same_triples(predicted, predicted2, "predicted", begin, end);
            for (std::size_t i = 0; i < kPassParticles; ++i) {
              ASSERT_EQ(std::bit_cast<std::uint64_t>(displacement2[i]),
                        std::bit_cast<std::uint64_t>(displacement2_made[i]))
                  << "displacement2 of particle " << i << " in [" << begin << ", " << end << ")";
            }
            ASSERT_EQ(std::bit_cast<std::uint64_t>(tally.largest2),
                      std::bit_cast<std::uint64_t>(largest2))
                << "[" << begin << ", " << end << ")";
            largest_seen = std::max(largest_seen, largest2);
          }
          ++ranges;
        }
      }
    }
  }
  EXPECT_GT(ranges, 1000u);
  // Particle 18 (one ulp beyond the limit) and the NaN ones are counted; 17 is not.
  EXPECT_GT(counted, 0u);
  // Particle 12's infinite force: an infinite displacement is the largest (the NaN of
  // particle 3 passed over).
  EXPECT_EQ(largest_seen, std::numeric_limits<double>::infinity());
}

// The step's first reaches and the displacements from the short list's anchors, made in the
// same pass (gvi_particle_passes.hpp's definition, as collect_by_particle_reach and
// NearbyRows::collect wrote them in passes of their own), with a floor above some
// displacements and below others.
TEST(GviParticlePasses, StepStartMakesTheReachesAndAnchoredDisplacements) {
  const double h = 0.005;
  const double list_limit2 = 1.0;
  const double tolerance = 1e-9;
  const PassInputs s = edge_inputs(list_limit2);
  std::mt19937_64 rng(12);
  std::vector<Vec3> anchor = s.position;
  std::uniform_real_distribution<double> drift(-0.2, 0.2);
  for (Vec3& a : anchor) a += Vec3{drift(rng), drift(rng), drift(rng)};
  std::size_t ranges = 0, floored = 0, above = 0;
  for (bool anchored : {true, false}) {
    for (std::size_t begin = 0; begin < 9; ++begin) {
      for (std::size_t end = begin; end <= kPassParticles; ++end) {
        std::vector<Vec3> q(kPassParticles), predicted(kPassParticles), p(kPassParticles),
            p_start(kPassParticles);
        std::vector<double> displacement2(kPassParticles), reach(kPassParticles, 9.0),
            limit2(kPassParticles, 9.0), moved(kPassParticles, 9.0);
        std::vector<double> reach_made = reach, limit2_made = limit2, moved_made = moved;
        gvi_passes::StepStart pass = step_start_inputs(s, h);
        pass.q = pass_numbers(q);
        pass.p = pass_numbers(p);
        pass.p_start = pass_numbers(p_start);
        pass.predicted = pass_numbers(predicted);
        pass.displacement2 = displacement2.data();
        // A floor near the middle of the displacements' squares (about 1e-4 here).
        pass.reach_floor2 = 6e-5;
        pass.gap_tolerance = tolerance;
        pass.reach = reach_made.data();
        pass.reach_limit2 = limit2_made.data();
        pass.anchor = anchored ? pass_numbers(anchor) : nullptr;
        pass.moved = moved_made.data();
        const gvi_passes::StepStartTally tally = gvi_passes::step_start(pass, begin, end);
        double anchored_largest2 = 0.0;  // as NearbyRows::collect's ordered_max took it
        for (std::size_t i = begin; i < end; ++i) {
          const double d2 = displacement2[i];
          floored += d2 < pass.reach_floor2 ? 1 : 0;
          above += d2 > pass.reach_floor2 ? 1 : 0;
          reach[i] = 2.0 * std::sqrt(d2 < pass.reach_floor2 ? pass.reach_floor2 : d2) + tolerance;
          limit2[i] = (reach[i] - 0.5 * tolerance) * (reach[i] - 0.5 * tolerance);
          if (!anchored) continue;
          const double a2 = norm2(s.position[i] - anchor[i]);
          anchored_largest2 = std::max(anchored_largest2, a2);
          moved[i] = std::sqrt(a2) + reach[i];
        }
        for (std::size_t i = 0; i < kPassParticles; ++i) {
          ASSERT_EQ(std::bit_cast<std::uint64_t>(reach[i]),
                    std::bit_cast<std::uint64_t>(reach_made[i]))
              << "reach of particle " << i << " in [" << begin << ", " << end << ")";
          ASSERT_EQ(std::bit_cast<std::uint64_t>(limit2[i]),
                    std::bit_cast<std::uint64_t>(limit2_made[i]))
              << "reach limit of particle " << i << " in [" << begin << ", " << end << ")";
          ASSERT_EQ(std::bit_cast<std::uint64_t>(moved[i]),
                    std::bit_cast<std::uint64_t>(moved_made[i]))
              << "anchored displacement of particle " << i << " in [" << begin << ", " << end
              << ")";
        }
        ASSERT_EQ(std::bit_cast<std::uint64_t>(tally.anchored_largest2),
                  std::bit_cast<std::uint64_t>(anchored_largest2))
            << "[" << begin << ", " << end << ")";
        ++ranges;
      }
    }
  }
  EXPECT_GT(ranges, 500u);
  EXPECT_GT(floored, 100u);
  EXPECT_GT(above, 100u);
}

TEST(GviParticlePasses, EndPositionsMakeTheVec3LoopsNumbersAndTally) {
  const double h = 0.005;
  const double list_limit2 = 1.0;
  const PassInputs s = edge_inputs(list_limit2);
  std::size_t ranges = 0;
  double largest_seen = 0.0;
  for (bool with_impulse : {true, false}) {
    for (bool with_reach : {true, false}) {
      for (bool listed : {true, false}) {
        for (std::size_t begin = 0; begin < 9; ++begin) {
          for (std::size_t end = begin; end <= kPassParticles; ++end) {
            // The definition, as displaced() wrote it (a missing impulse is +0).
            std::vector<Vec3> x(kPassParticles, Vec3{3, 3, 3}), x2 = x;
            double largest = 0.0;
            std::size_t beyond = 0, beyond_list = 0;
            for (std::size_t i = begin; i < end; ++i) {
              const Vec3 held = with_impulse ? s.impulse[i] : Vec3{};
              x[i] = s.position[i] + (s.half[i] + held) * (h / s.mass[i]);
              const double moved2 = norm2(x[i] - s.position[i]);
              largest = std::max(largest, moved2);
              if (with_reach) beyond += !(moved2 <= s.reach[i]);
              if (listed) beyond_list += !(norm2(x[i] - s.at_build[i]) <= list_limit2);
            }
            gvi_passes::EndPositions pass;
            pass.h = h;
            pass.q = pass_numbers(s.position);
            pass.half = pass_numbers(s.half);
            pass.impulse = with_impulse ? pass_numbers(s.impulse) : nullptr;
            pass.mass = s.mass.data();
            pass.reach_limit2 = with_reach ? s.reach.data() : nullptr;
            pass.at_build = listed ? pass_numbers(s.at_build) : nullptr;
            pass.list_limit2 = list_limit2;
            pass.x = pass_numbers(x2);
            const gvi_passes::EndPositionsTally tally = gvi_passes::end_positions(pass, begin, end);
            ASSERT_EQ(std::bit_cast<std::uint64_t>(tally.largest2),
                      std::bit_cast<std::uint64_t>(largest))
                << "[" << begin << ", " << end << ")";
            ASSERT_EQ(tally.beyond_reach, beyond) << "[" << begin << ", " << end << ")";
            ASSERT_EQ(tally.beyond_list, beyond_list) << "[" << begin << ", " << end << ")";
            expect_same_triples(x, x2, "x", begin, end);
            largest_seen = std::max(largest_seen, largest);
            ++ranges;
          }
        }
      }
    }
  }
  EXPECT_GT(ranges, 2000u);
  EXPECT_GT(largest_seen, 0.0);
}

TEST(GviParticlePasses, HalfKickMakesTheVec3LoopsNumbers) {
  const double h = 0.005;
  const PassInputs s = edge_inputs(1.0);
  for (int outputs = 1; outputs < 4; ++outputs) {
    const bool with_half = outputs & 1, with_free = outputs & 2;
    for (std::size_t begin = 0; begin < 9; ++begin) {
      for (std::size_t end = begin; end <= kPassParticles; ++end) {
        // Gvi's half_kicked and free_step, from the momenta (here the velocities' numbers).
        std::vector<Vec3> half(kPassParticles, Vec3{5, 5, 5}), half2 = half;
        std::vector<Vec3> free(kPassParticles, Vec3{4, 4, 4}), free2 = free;
        for (std::size_t i = begin; i < end; ++i) {
          const Vec3 kicked = s.velocity[i] + s.force[i] * (0.5 * h);
          if (with_half) half[i] = kicked;
          if (with_free) free[i] = kicked * (h / s.mass[i]);
        }
        gvi_passes::half_kick(h, pass_numbers(s.velocity), pass_numbers(s.force), s.mass.data(),
                              with_half ? pass_numbers(half2) : nullptr,
                              with_free ? pass_numbers(free2) : nullptr, begin, end);
        expect_same_triples(half, half2, "half", begin, end);
        expect_same_triples(free, free2, "free", begin, end);
      }
    }
  }
}

TEST(GviParticlePasses, MomentaAndVelocitiesMakeTheVec3LoopsNumbers) {
  const double h = 0.005;
  const PassInputs s = edge_inputs(1.0);
  for (bool with_impulse : {true, false}) {
    for (std::size_t begin = 0; begin < 9; ++begin) {
      for (std::size_t end = begin; end <= kPassParticles; ++end) {
        // update_momenta's definitions (a missing impulse is +0).
        std::vector<Vec3> p(kPassParticles, Vec3{5, 5, 5}), p2 = p;
        std::vector<Vec3> v(kPassParticles, Vec3{4, 4, 4}), v2 = v;
        for (std::size_t i = begin; i < end; ++i) {
          Vec3 momentum = s.half[i] + (with_impulse ? s.impulse[i] : Vec3{});
          momentum += s.force[i] * (0.5 * h);
          p[i] = momentum;
          v[i] = p[i] * (1.0 / s.mass[i]);
        }
        gvi_passes::second_kick(h, pass_numbers(s.half),
                                with_impulse ? pass_numbers(s.impulse) : nullptr,
                                pass_numbers(s.force), pass_numbers(p2), begin, end);
        expect_same_triples(p, p2, "p", begin, end);
        gvi_passes::velocities(pass_numbers(p2), s.mass.data(), pass_numbers(v2), begin, end);
        expect_same_triples(v, v2, "velocity", begin, end);
      }
    }
  }
}

// kicked_velocities makes second_kick's momenta a block of 64 particles at a time: over four
// copies of the edge inputs (160 particles), on ranges that start inside the first block and
// end in every block, its velocities are second_kick's then velocities', bit for bit.
TEST(GviParticlePasses, KickedVelocitiesAreTheKickThenTheVelocities) {
  const double h = 0.005;
  const PassInputs one = edge_inputs(1.0);
  std::vector<Vec3> half, impulse, force;
  std::vector<double> mass;
  for (int copy = 0; copy < 4; ++copy) {
    half.insert(half.end(), one.half.begin(), one.half.end());
    impulse.insert(impulse.end(), one.impulse.begin(), one.impulse.end());
    force.insert(force.end(), one.force.begin(), one.force.end());
    mass.insert(mass.end(), one.mass.begin(), one.mass.end());
  }
  const std::size_t n = mass.size();
  for (bool with_impulse : {true, false}) {
    const double* b = with_impulse ? pass_numbers(impulse) : nullptr;
    for (std::size_t begin = 0; begin < 9; ++begin) {
      for (std::size_t end = begin; end <= n; ++end) {
        std::vector<Vec3> p(n, Vec3{5, 5, 5}), v(n, Vec3{4, 4, 4}), v2 = v;
        gvi_passes::second_kick(h, pass_numbers(half), b, pass_numbers(force), pass_numbers(p),
                                begin, end);
        gvi_passes::velocities(pass_numbers(p), mass.data(), pass_numbers(v), begin, end);
        gvi_passes::kicked_velocities(h, pass_numbers(half), b, pass_numbers(force), mass.data(),
                                      pass_numbers(v2), begin, end);
        expect_same_triples(v, v2, "velocity", begin, end);
      }
    }
  }
}

}  // namespace
}  // namespace deli
