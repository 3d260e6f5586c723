// The Lennard-Jones pair loop's vector form (PairForce with one type and an image-coded
// list: LennardJones::vector_loop, AVX-512 or AVX2 where the build has it) against the definition,
// every pair of particles by minimum image with r^2 < cutoff^2 (strict), and against the
// scalar loop (the same model as a two-type table, which PairForce runs pair by pair). The
// vector loop sums a particle's pairs by lane, so the forces agree to round-off (1e-12 of the
// largest force), not bit for bit; energy and virial are summed in the scalar order (its
// bits). Without AVX-512 or AVX2 in the build both sides are scalar and the
// test still checks the loop against the definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "neighbor/neighbor_list.hpp"
#include "pair/lennard_jones.hpp"
#include "pair/pair_force.hpp"

namespace deli {
namespace {

constexpr double kCutoff = 2.5, kSkin = 0.3;

struct PairResult {
  std::vector<Vec3> force;
  SymTensor virial;
  double energy = 0.0;
};

// A PairForce of `types` types whose pairs a, b take table[a * types + b].
PairForce<LennardJones> make_term(int types, const std::vector<LennardJones::Params>& table) {
  return PairForce<LennardJones>("pair", types, table, true, kCutoff, {});
}

NeighborList built_list(const System& system, bool cell_order) {
  NeighborList list(kCutoff, kSkin);
  list.set_cell_order(cell_order);
  list.build(system.particles.position, system.box);
  EXPECT_FALSE(list.image_codes().empty()) << "the box should be wide enough for image codes";
  return list;
}

PairResult run_term(const PairForce<LennardJones>& term, const System& system, bool cell_order,
                    bool tally = true) {
  const NeighborList list = built_list(system, cell_order);
  PairResult r;
  r.force.assign(system.particles.size(), Vec3{});
  r.energy = term.compute(system, list, r.force, r.virial, tally);
  return r;
}

// The definition: every pair once, by minimum image, inside its type pair's cutoff.
PairResult definition(const System& system, int types,
                      const std::vector<LennardJones::Params>& table) {
  const Particles& p = system.particles;
  PairResult r;
  r.force.assign(p.size(), Vec3{});
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const LennardJones::Params& q =
          table[static_cast<std::size_t>(p.type[i] * types + p.type[j])];
      const Vec3 d = system.box.minimum_image(p.position[i] - p.position[j]);
      const double r2 = norm2(d);
      if (!(r2 < q.cutoff2)) continue;
      double f_over_r, e;
      LennardJones::evaluate(q, r2, f_over_r, e);
      const Vec3 f = d * f_over_r;
      r.force[i] += f;
      r.force[j] -= f;
      r.energy += e - LennardJones::cutoff_energy(q);
      r.virial.add_outer(d, f);
    }
  }
  return r;
}

void expect_close(const PairResult& a, const PairResult& b, const char* what) {
  double scale = 0.0;
  for (const Vec3& f : b.force) scale = std::max(scale, std::sqrt(norm2(f)));
  ASSERT_GT(scale, 0.0);
  for (std::size_t i = 0; i < a.force.size(); ++i) {
    EXPECT_LE(std::sqrt(norm2(a.force[i] - b.force[i])), 1e-12 * scale)
        << what << ", particle " << i;
  }
  EXPECT_NEAR(a.energy, b.energy, 1e-12 * std::abs(b.energy)) << what;
  const double w = std::abs(b.virial.trace());
  EXPECT_NEAR(a.virial.xx, b.virial.xx, 1e-12 * w) << what;
  EXPECT_NEAR(a.virial.yy, b.virial.yy, 1e-12 * w) << what;
  EXPECT_NEAR(a.virial.zz, b.virial.zz, 1e-12 * w) << what;
  EXPECT_NEAR(a.virial.xy, b.virial.xy, 1e-12 * w) << what;
  EXPECT_NEAR(a.virial.xz, b.virial.xz, 1e-12 * w) << what;
  EXPECT_NEAR(a.virial.yz, b.virial.yz, 1e-12 * w) << what;
}

// A jittered simple cubic lattice (spacing 1.1, so no two particles much closer than 0.5)
// in a periodic box of 9 cells (9.9 > 3 x (cutoff + skin): image-coded lists), with a
// fraction of the sites left empty: list lengths of every remainder modulo 8.
System lattice_liquid(unsigned seed, double vacancy) {
  constexpr int cells = 9;
  constexpr double spacing = 1.1;
  System system;
  system.box =
      Box({0, 0, 0}, {cells * spacing, cells * spacing, cells * spacing}, {true, true, true});
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), u(0.0, 1.0);
  std::vector<Vec3> x;
  for (int a = 0; a < cells; ++a) {
    for (int b = 0; b < cells; ++b) {
      for (int c = 0; c < cells; ++c) {
        if (u(rng) < vacancy) continue;
        x.push_back({(a + 0.5) * spacing + jitter(rng), (b + 0.5) * spacing + jitter(rng),
                     (c + 0.5) * spacing + jitter(rng)});
      }
    }
  }
  system.particles.resize(x.size());
  system.particles.position = x;
  return system;
}

TEST(LjVectorLoop, MatchesDefinitionAndScalarLoopOnRandomLiquids) {
  const LennardJones::Params lj = LennardJones::make(1.0, 1.0, kCutoff);
  const PairForce<LennardJones> one_type = make_term(1, {lj});
  const PairForce<LennardJones> two_types = make_term(2, {lj, lj, lj, lj});  // the scalar loop
  for (const unsigned seed : {1u, 2u, 3u}) {
    for (const double vacancy : {0.0, 0.2, 0.5}) {
      const System system = lattice_liquid(seed, vacancy);
      const PairResult exact = definition(system, 1, {lj});
      // The cases the vector loop distinguishes occur: partial last vectors of every length
      // and vectors with a periodic image's shift.
      const NeighborList list = built_list(system, false);
      std::vector<bool> remainder(8, false);
      for (std::size_t i = 0; i + 1 < list.offsets().size(); ++i) {
        remainder[(list.offsets()[i + 1] - list.offsets()[i]) % 8] = true;
      }
      EXPECT_EQ(std::count(remainder.begin(), remainder.end(), true), 8);
      EXPECT_GT(std::count_if(list.image_codes().begin(), list.image_codes().end(),
                              [](std::uint8_t code) { return code != 0; }),
                0);
      for (const bool cell_order : {false, true}) {
        const PairResult vector = run_term(one_type, system, cell_order);
        const PairResult scalar = run_term(two_types, system, cell_order);
        expect_close(vector, exact, "vector loop against the definition");
        expect_close(vector, scalar, "vector loop against the scalar loop");
        // Energy and virial in the scalar loop's order: its bits.
        EXPECT_EQ(vector.energy, scalar.energy);
        EXPECT_EQ(vector.virial.xx, scalar.virial.xx);
        EXPECT_EQ(vector.virial.yy, scalar.virial.yy);
        EXPECT_EQ(vector.virial.zz, scalar.virial.zz);
        EXPECT_EQ(vector.virial.xy, scalar.virial.xy);
        EXPECT_EQ(vector.virial.xz, scalar.virial.xz);
        EXPECT_EQ(vector.virial.yz, scalar.virial.yz);
        // Without the tally the same forces, bit for bit.
        const PairResult untallied = run_term(one_type, system, cell_order, false);
        for (std::size_t i = 0; i < system.particles.size(); ++i) {
          ASSERT_EQ(untallied.force[i].x, vector.force[i].x);
          ASSERT_EQ(untallied.force[i].y, vector.force[i].y);
          ASSERT_EQ(untallied.force[i].z, vector.force[i].z);
        }
      }
    }
  }
}

// Pairs exactly at the cutoff (r^2 == cutoff^2: out, the test is strict) and 2^-40 inside
// it (separations exact in doubles), directly and across a periodic boundary; each particle has one
// partner, so every sum has one term and the vector loop gives the scalar loop's bits.
TEST(LjVectorLoop, PairsAtTheCutoffAsTheScalarLoop) {
  System system;
  system.box = Box({0, 0, 0}, {10, 10, 10}, {true, true, true});
  const double inside = kCutoff - 0x1p-40;
  const std::vector<Vec3> x = {
      {1.0, 1.0, 1.0},           {1.0 + kCutoff, 1.0, 1.0},  // at the cutoff
      {1.0, 4.0, 1.0},           {1.0 + inside, 4.0, 1.0},   // just inside
      {0.5, 7.0, 1.0},           {8.0, 7.0, 1.0},            // at the cutoff through the boundary
      {2.0 - 0x1p-40, 7.0, 5.0}, {9.5, 7.0, 5.0},            // just inside through the boundary
      {5.0, 1.0, 8.0},           {5.0, 1.0 + 2.0, 8.0},      // well inside
  };
  system.particles.resize(x.size());
  system.particles.position = x;
  const LennardJones::Params lj = LennardJones::make(1.0, 1.0, kCutoff);
  for (const bool cell_order : {false, true}) {
    const PairResult vector = run_term(make_term(1, {lj}), system, cell_order);
    const PairResult scalar = run_term(make_term(2, {lj, lj, lj, lj}), system, cell_order);
    for (std::size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(vector.force[i].x, scalar.force[i].x) << i;
      EXPECT_EQ(vector.force[i].y, scalar.force[i].y) << i;
      EXPECT_EQ(vector.force[i].z, scalar.force[i].z) << i;
    }
    EXPECT_EQ(vector.force[0].x, 0.0);  // the pairs at the cutoff: no force
    EXPECT_EQ(vector.force[4].x, 0.0);
    EXPECT_NE(vector.force[2].x, 0.0);  // just inside: a force
    EXPECT_NE(vector.force[6].x, 0.0);
  }
}

// Two clusters of 27 at opposite corners of the box: each particle's partners in the other
// cluster are all through one periodic image, the corner's (every axis shifted), so whole
// vectors of eight partners share that code; still the definition.
TEST(LjVectorLoop, VectorsThroughOneCornerImage) {
  System system;
  system.box = Box({0, 0, 0}, {10, 10, 10}, {true, true, true});
  std::vector<Vec3> x;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      for (int c = 0; c < 3; ++c) {
        x.push_back({0.2 + 0.8 * a, 0.2 + 0.8 * b, 0.2 + 0.8 * c});
        x.push_back({9.8 - 0.8 * a, 9.8 - 0.8 * b, 9.8 - 0.8 * c});
      }
    }
  }
  system.particles.resize(x.size());
  system.particles.position = x;
  const LennardJones::Params lj = LennardJones::make(1.0, 1.0, kCutoff);
  const PairResult exact = definition(system, 1, {lj});
  for (const bool cell_order : {false, true}) {
    // The case occurs: a whole vector (eight partners from a multiple of eight) through one
    // shifted image.
    const NeighborList list = built_list(system, cell_order);
    const std::vector<std::size_t>& offsets =
        cell_order ? list.cell_ordered().offsets : list.offsets();
    const std::vector<std::uint8_t>& codes =
        cell_order ? list.cell_ordered().image_codes : list.image_codes();
    bool shifted_vector = false;
    for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
      for (std::size_t k = offsets[i]; k + 8 <= offsets[i + 1]; k += 8) {
        const Vec3& s = list.image_shifts()[codes[k]];
        shifted_vector |= std::all_of(codes.begin() + static_cast<std::ptrdiff_t>(k),
                                      codes.begin() + static_cast<std::ptrdiff_t>(k + 8),
                                      [&](std::uint8_t c) { return c == codes[k]; }) &&
                          s.x != 0.0 && s.y != 0.0 && s.z != 0.0;
      }
    }
    EXPECT_TRUE(shifted_vector);
    expect_close(run_term(make_term(1, {lj}), system, cell_order), exact, "corner images");
  }
}

// The vector loop (where built: AVX-512 or AVX2) and its one-pair-at-a-time form, which a
// portable build runs: the same forces, energy and virial bit for bit. Each also reads the list in
// place through the build's ranges (VectorPairChunk::ends, the list as built: particle i's
// partners not at offsets[i + 1]) with the same bits as through the list by particle.
TEST(LjVectorLoop, OnePairAtATimeGivesTheVectorLoopsBits) {
  const LennardJones::Params lj = LennardJones::make(1.0, 1.0, kCutoff);
  for (const double vacancy : {0.0, 0.3}) {
    const System system = lattice_liquid(5, vacancy);
    const NeighborList list = built_list(system, false);
    const NeighborList::PartnerRanges built = list.built_order();
    ASSERT_NE(built.end, nullptr);
    const std::size_t n = system.particles.size();
    // The list as built is in another order than the list by particle.
    bool moved = false;
    for (std::size_t i = 0; i < n; ++i) moved = moved || built.begin[i] != list.offsets()[i];
    ASSERT_TRUE(moved);
    std::vector<PaddedVec3> x(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& p = system.particles.position[i];
      x[i] = {p.x, p.y, p.z, 0.0};
    }
    struct Run {
      std::vector<PaddedVec3> f;
      SymTensor w;
      double e;
    };
    auto run = [&](bool in_place, bool by_vector) {
      Run r{std::vector<PaddedVec3>(n), {}, 0.0};
      const VectorPairChunk chunk{x.data(),
                                  r.f.data(),
                                  in_place ? built.neighbors : list.neighbors().data(),
                                  in_place ? built.image_codes : list.image_codes().data(),
                                  in_place ? built.begin : list.offsets().data(),
                                  list.image_shifts().data(),
                                  0,
                                  static_cast<std::int32_t>(n),
                                  in_place ? built.end : nullptr};
      r.e = by_vector ? LennardJones::vector_loop(lj, chunk, true, r.w)
                      : LennardJones::lane_order_loop(lj, chunk, true, r.w);
      return r;
    };
    const Run vector = run(false, true);
    for (const auto& [in_place, by_vector] :
         {std::pair{false, false}, std::pair{true, true}, std::pair{true, false}}) {
      const Run other = run(in_place, by_vector);
      EXPECT_EQ(other.e, vector.e);
      EXPECT_EQ(other.w.xx, vector.w.xx);
      EXPECT_EQ(other.w.yz, vector.w.yz);
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(other.f[i].x, vector.f[i].x) << i << " in place " << in_place;
        ASSERT_EQ(other.f[i].y, vector.f[i].y) << i;
        ASSERT_EQ(other.f[i].z, vector.f[i].z) << i;
      }
    }
  }
  if (!LennardJones::vector_loop_built()) GTEST_SKIP() << "no vector loop in this build";
}

// Two types with different parameters take the scalar loop (the vector loop has one parameter
// set): still the definition.
TEST(LjVectorLoop, SeveralTypesFallBackToTheScalarLoop) {
  System system = lattice_liquid(4, 0.1);
  for (std::size_t i = 0; i < system.particles.size(); ++i) system.particles.type[i] = i % 2;
  const LennardJones::Params aa = LennardJones::make(1.0, 1.0, kCutoff);
  const LennardJones::Params ab = LennardJones::make(0.7, 0.9, 2.2);
  const LennardJones::Params bb = LennardJones::make(1.3, 0.8, 2.0);
  const std::vector<LennardJones::Params> table = {aa, ab, ab, bb};
  const PairResult exact = definition(system, 2, table);
  for (const bool cell_order : {false, true}) {
    expect_close(run_term(make_term(2, table), system, cell_order), exact, "two types");
  }
}

// The shadow energy's curvature sum, v^T H v over the listed pairs (PairForce::pair_curvature):
// with one type LennardJones::curvature_loop (by vector where built), with the
// same model as a two-type table PairForce's pair-by-pair sum. Each term is the scalar one's
// bits and the terms are added in list order, so the two sums are equal bit for bit; both
// agree with the definition (every pair by minimum image, its Hessian block's closed form
// phi'' (u.w)^2 - (f/r) (|w|^2 - (u.w)^2)) to round-off. Lists of every length modulo 8,
// pairs through periodic images, a non-periodic axis, and pairs at and just inside the cutoff.
TEST(LjVectorLoop, CurvatureSumIsThePairByPairSumsBits) {
  const LennardJones::Params lj = LennardJones::make(1.0, 1.0, kCutoff);
  const PairForce<LennardJones> one_type = make_term(1, {lj});
  const PairForce<LennardJones> two_types = make_term(2, {lj, lj, lj, lj});
  auto curvature = [](const PairForce<LennardJones>& term, const System& system,
                      const std::vector<Vec3>& v) {
    NeighborList list(kCutoff, kSkin);
    list.build(system.particles.position, system.box);
    double sum = 0.0;
    EXPECT_TRUE(term.pair_curvature(system, list, v, sum));
    return sum;
  };
  auto definition_sum = [&](const System& system, const std::vector<Vec3>& v, double& magnitude) {
    const std::vector<Vec3>& x = system.particles.position;
    double sum = 0.0;
    magnitude = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      for (std::size_t j = i + 1; j < x.size(); ++j) {
        const Vec3 d = system.box.minimum_image(x[i] - x[j]);
        const double r2 = norm2(d);
        if (!(r2 < lj.cutoff2)) continue;
        double f_over_r, e;
        LennardJones::evaluate(lj, r2, f_over_r, e);
        const Vec3 w = v[i] - v[j];
        const double along2 = dot(d, w) * dot(d, w) / r2;
        const double term =
            LennardJones::second_derivative(lj, r2) * along2 - f_over_r * (norm2(w) - along2);
        sum += term;
        magnitude += std::abs(term);
      }
    }
    return sum;
  };
  std::mt19937_64 rng(23);
  std::normal_distribution<double> gauss;
  auto velocities = [&](std::size_t n) {
    std::vector<Vec3> v(n);
    for (Vec3& u : v) u = {gauss(rng), gauss(rng), gauss(rng)};
    return v;
  };
  for (const bool periodic_z : {true, false}) {
    for (const double vacancy : {0.0, 0.3}) {
      System system = lattice_liquid(7, vacancy);
      if (!periodic_z) {
        system.box = Box(system.box.lo(), system.box.hi(), {true, true, false});
      }
      const std::vector<Vec3> v = velocities(system.particles.size());
      const double vector = curvature(one_type, system, v);
      EXPECT_EQ(vector, curvature(two_types, system, v)) << "periodic z " << periodic_z;
      double magnitude = 0.0;
      const double exact = definition_sum(system, v, magnitude);
      ASSERT_GT(magnitude, 0.0);
      EXPECT_NEAR(vector, exact, 1e-12 * magnitude) << "periodic z " << periodic_z;
    }
  }
  // Pairs at the cutoff (out) and 2^-40 inside it, directly and through the boundary.
  System edge;
  edge.box = Box({0, 0, 0}, {10, 10, 10}, {true, true, true});
  const double inside = kCutoff - 0x1p-40;
  edge.particles.resize(8);
  edge.particles.position = {{1.0, 1.0, 1.0},           {1.0 + kCutoff, 1.0, 1.0},
                             {1.0, 4.0, 1.0},           {1.0 + inside, 4.0, 1.0},
                             {0.5, 7.0, 1.0},           {8.0, 7.0, 1.0},
                             {2.0 - 0x1p-40, 7.0, 5.0}, {9.5, 7.0, 5.0}};
  const std::vector<Vec3> v = velocities(8);
  const double at_edge = curvature(one_type, edge, v);
  EXPECT_EQ(at_edge, curvature(two_types, edge, v));
  double magnitude = 0.0;
  EXPECT_EQ(at_edge, definition_sum(edge, v, magnitude));  // two terms: the same two additions
  EXPECT_NE(at_edge, 0.0);
  if (!LennardJones::curvature_loop_built()) GTEST_SKIP() << "no vector curvature in this build";
}

}  // namespace
}  // namespace deli
