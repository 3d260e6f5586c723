// NearbyRows::collect against ConstraintSet::nearby_inequalities (the plain scan of the
// neighbour list, one reach for all) filtered by the definition: with one reach, the same
// rows in the same order; with a reach per particle, exactly the rows whose gap is within
// their two particles' reaches summed (a wall row: twice its particle's), still in the
// scan's order; gaps at q evaluate()'s wherever they may be within `exact_below`. Hard
// spheres of diameter 1 in a periodic box with a plane wall, collected at the start
// positions and again after every particle moved (the short list then serves unchanged).
// The same fluid's smallest gap (ConstraintSet::minimum_gap) against its definition.
#include "constraints/nearby_rows.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <random>
#include <string>

#include "core/parallel.hpp"
#include "neighbor/neighbor_list.hpp"
#include "support/thread_count.hpp"

namespace deli {
namespace {

struct NearbyRowsFluid {
  Box box{{0, 0, 0}, {7, 7, 7}, {true, true, true}};
  Particles particles;
  ConstraintSet set;
  std::vector<double> reach;  // per particle
};

NearbyRowsFluid nearby_rows_fluid(std::size_t n, std::uint64_t seed) {
  NearbyRowsFluid fluid;
  fluid.particles.resize(n);
  fluid.set.hard_spheres = true;
  fluid.set.walls.push_back({ConstraintKind::plane, {0, 0, 0.5}, {0, 0, 1}});
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 7.0), speed(0.0, 0.05);
  for (std::size_t i = 0; i < n; ++i) {
    fluid.particles.position[i] = {u(rng), u(rng), u(rng)};
    fluid.particles.radius[i] = 0.5;
    fluid.reach.push_back(speed(rng));
  }
  return fluid;
}

// The plain scan's rows within their particle reaches, and the exact gaps of all of them.
std::vector<Constraint> nearby_rows_reference(const NearbyRowsFluid& fluid, const Vec3* q,
                                              const NeighborList& list, double widest,
                                              const double* reach) {
  std::vector<Constraint> kept;
  for (const Constraint& c :
       fluid.set.nearby_inequalities(fluid.particles, q, list, fluid.box, widest)) {
    const double row_reach = !reach ? widest : c.j < 0 ? 2.0 * reach[c.i] : reach[c.i] + reach[c.j];
    if (evaluate(c, q, fluid.box).gap <= row_reach) kept.push_back(c);
  }
  return kept;
}

void expect_nearby_rows(const NearbyRowsFluid& fluid, NearbyRows& rows, const Vec3* q,
                        const NeighborList& list, bool per_particle) {
  const double gap_tolerance = 1e-10;
  const double widest = 0.1;  // at least twice every particle reach
  const double* reach = per_particle ? fluid.reach.data() : nullptr;
  std::vector<Constraint> out;
  std::vector<double> gap_at_q;
  rows.collect(fluid.set, fluid.particles, q, list, fluid.box, widest, reach, gap_tolerance, out,
               gap_at_q);
  const std::vector<Constraint> expected = nearby_rows_reference(fluid, q, list, widest, reach);
  ASSERT_EQ(out.size(), expected.size());
  ASSERT_EQ(gap_at_q.size(), out.size());
  std::size_t pairs = 0;
  for (std::size_t k = 0; k < out.size(); ++k) {
    EXPECT_TRUE(same_row(out[k], expected[k])) << "row " << k;
    const double gap = evaluate(expected[k], q, fluid.box).gap;
    if (gap_at_q[k] <= gap_tolerance || gap <= gap_tolerance) EXPECT_EQ(gap_at_q[k], gap);
    pairs += expected[k].j >= 0;
  }
  // Both kinds of rows are met.
  EXPECT_GT(pairs, 10u);
  EXPECT_LT(pairs, out.size());
}

TEST(NearbyRows, RowsWithinTheReachInTheScansOrder) {
  for (const bool per_particle : {false, true}) {
    NearbyRowsFluid fluid = nearby_rows_fluid(400, per_particle ? 3 : 4);
    NeighborList list(1.0, 0.4);
    list.build(fluid.particles.position, fluid.box);
    NearbyRows rows;
    std::vector<Vec3> q = fluid.particles.position;
    expect_nearby_rows(fluid, rows, q.data(), list, per_particle);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    for (Vec3& x : q) x += Vec3{u(rng), u(rng), u(rng)};
    expect_nearby_rows(fluid, rows, q.data(), list, per_particle);
  }
}

// Spheres of two sizes (radius 0.5 and 0.05, alternating), each even particle bonded to the
// next, placed 0.01 beyond contact (bonded pairs have no contact row): the short list's first
// test then takes each pair's own contact distance, and drops the bonded pairs it meets, as
// the plain scan does. With one contact distance for all taken from the owner, a pair whose
// owner is small would be dropped from the short list beyond 0.1 + margin 0.5, short of its
// 0.55 + reach.
TEST(NearbyRows, SpheresOfTwoSizesAndBondedPairs) {
  for (const bool per_particle : {false, true}) {
    NearbyRowsFluid fluid = nearby_rows_fluid(400, per_particle ? 11 : 12);
    for (std::size_t i = 0; i < fluid.particles.size(); ++i) {
      fluid.particles.radius[i] = i % 2 == 0 ? 0.5 : 0.05;
    }
    for (std::size_t i = 0; i + 1 < fluid.particles.size(); i += 2) {
      const auto a = static_cast<std::int32_t>(i);
      fluid.set.unconstrained_pairs.push_back({a, a + 1});
      Vec3 partner = fluid.particles.position[i] + Vec3{0.56, 0.0, 0.0};
      std::array<int, 3> image{};
      fluid.box.wrap(partner, image);
      fluid.particles.position[i + 1] = partner;
    }
    NeighborList list(1.0, 0.4);
    list.build(fluid.particles.position, fluid.box);
    NearbyRows rows;
    std::vector<Vec3> q = fluid.particles.position;
    expect_nearby_rows(fluid, rows, q.data(), list, per_particle);
  }
}

// On two threads the list's scan and the screen (both cheap items) run in chunks joined in
// chunk order: the same rows, in the same order, with the same gaps bit for bit as on one
// thread, and those of the plain scan. In chunks of at least 512 items, the 1200 particles'
// scan is cut in two and each thread screens its own chunk's pairs; of at least 1000, the scan
// is whole and its pairs (several times the rows) are cut in two for the screen.
TEST(NearbyRows, TwoThreadsCollectTheOneThreadRows) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#endif
  const NearbyRowsFluid fluid = nearby_rows_fluid(1200, 5);
  NeighborList list(1.0, 0.4);
  list.build(fluid.particles.position, fluid.box);
  std::vector<Vec3> q = fluid.particles.position;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  std::vector<Vec3> moved = q;
  for (Vec3& x : moved) x += Vec3{u(rng), u(rng), u(rng)};
  struct Collected {
    std::vector<Constraint> rows;
    std::vector<double> gaps;
  };
  auto collect = [&](int threads, std::size_t minimum) {
    const int before = thread_count();
    const std::size_t cheap_before = cheap_chunk_minimum();
    set_thread_count(threads);
    set_cheap_chunk_minimum(minimum);
    NearbyRows rows;
    std::vector<Collected> out(2);
    for (std::size_t pass = 0; pass < 2; ++pass) {
      const Vec3* at = pass == 0 ? q.data() : moved.data();
      rows.collect(fluid.set, fluid.particles, at, list, fluid.box, 0.1, fluid.reach.data(), 1e-10,
                   out[pass].rows, out[pass].gaps);
      if (threads == 2) expect_nearby_rows(fluid, rows, at, list, true);
    }
    set_thread_count(before);
    set_cheap_chunk_minimum(cheap_before);
    return out;
  };
  for (const std::size_t minimum : {std::size_t{512}, std::size_t{1000}}) {
    SCOPED_TRACE(minimum);
    const std::vector<Collected> one = collect(1, minimum), two = collect(2, minimum);
    for (std::size_t pass = 0; pass < 2; ++pass) {
      // Enough rows that both chunks keep some (the screened pairs are several times more).
      EXPECT_GT(one[pass].rows.size(), kParallelMinimum);
      ASSERT_EQ(one[pass].rows.size(), two[pass].rows.size());
      for (std::size_t k = 0; k < one[pass].rows.size(); ++k) {
        EXPECT_TRUE(same_row(one[pass].rows[k], two[pass].rows[k])) << "row " << k;
        EXPECT_EQ(one[pass].gaps[k], two[pass].gaps[k]) << "row " << k;
      }
    }
  }
}

// ConstraintSet::minimum_gap (the thermo's min_gap) is the smallest gap over every pair not
// bonded and every wall row, by definition (every pair of the 1200 spheres at the minimum
// image, evaluate()'s gaps): exactly, on one thread and on two (chunks of particles, each
// with its own running bound). With the walls taken away and the last two spheres 0.01 apart
// (the closest pair, in the second chunk), then with that pair among the bonded pairs (the
// next one is then the smallest), then with the last sphere on the wall.
TEST(ConstraintSetMinimumGap, TheSmallestOverEveryUnbondedPairAndWallOnAnyThreadCount) {
  NearbyRowsFluid fluid = nearby_rows_fluid(1200, 9);
  const std::size_t n = fluid.particles.size();
  const Vec3* x = fluid.particles.position.data();
  struct Smallest {
    double gap = std::numeric_limits<double>::infinity();
    Constraint row;
  };
  auto by_definition = [&] {
    Smallest out;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        const std::array<std::int32_t, 2> pair{static_cast<std::int32_t>(i),
                                               static_cast<std::int32_t>(j)};
        const std::vector<std::array<std::int32_t, 2>>& bonded = fluid.set.unconstrained_pairs;
        if (std::find(bonded.begin(), bonded.end(), pair) != bonded.end()) continue;
        const Constraint c = sphere_pair(pair[0], pair[1], fluid.particles);
        const double gap = evaluate(c, x, fluid.box).gap;
        if (gap < out.gap) out = {gap, c};
      }
      for (const Wall& wall : fluid.set.walls) {
        const Constraint c =
            fluid.set.wall_row(wall, static_cast<std::int32_t>(i), fluid.particles.radius[i]);
        const double gap = evaluate(c, x, fluid.box).gap;
        if (gap < out.gap) out = {gap, c};
      }
    }
    return out;
  };
  auto expect_minimum = [&](const Smallest& expected) {
    NeighborList list(1.0, 0.4);
    list.build(fluid.particles.position, fluid.box);
    const int before = thread_count();
    for (const int threads : {1, 2}) {
#ifndef _OPENMP
      if (threads > 1) continue;
#endif
      SCOPED_TRACE(std::to_string(threads) + " thread(s)");
      set_thread_count(threads);
      EXPECT_EQ(chunks_for(n), threads);
      EXPECT_EQ(fluid.set.minimum_gap(fluid.particles, x, list, fluid.box), expected.gap);
    }
    set_thread_count(before);
  };
  const std::vector<Wall> walls = fluid.set.walls;
  fluid.set.walls.clear();
  fluid.particles.position[n - 2] = fluid.particles.position[n - 1] + Vec3{0.01, 0, 0};
  const Smallest closest = by_definition();
  ASSERT_EQ(closest.row.kind, ConstraintKind::sphere_pair);
  ASSERT_EQ(closest.row.i, static_cast<std::int32_t>(n - 2));
  expect_minimum(closest);
  fluid.set.unconstrained_pairs.push_back({closest.row.i, closest.row.j});
  const Smallest next = by_definition();
  ASSERT_GT(next.gap, closest.gap);
  expect_minimum(next);
  fluid.set.walls = walls;
  fluid.particles.position[n - 1].z = 0.01;  // the plane at z 0.5: gap -0.99
  const Smallest on_wall = by_definition();
  ASSERT_EQ(on_wall.row.kind, ConstraintKind::plane);
  expect_minimum(on_wall);
}

}  // namespace
}  // namespace deli
