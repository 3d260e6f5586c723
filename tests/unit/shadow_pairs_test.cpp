// The shadow-energy reflections' parts split across threads: each reflected cluster's pairs
// made from the pair Hessian blocks in chunks of blocks (ShadowPairs) are, on one thread and
// on two, the pairs of a scan of the blocks for that cluster alone (the serial definition,
// written out here); and reflect() with a shadow operator, whose Hessian products are made on
// as many threads as there are products, gives the same momenta bit for bit on one thread
// and on two.
#include "integrators/shadow_pairs.hpp"

#include <gtest/gtest.h>

#include <random>
#include <utility>

#include "constraints/constraint_set.hpp"
#include "core/parallel.hpp"
#include "support/thread_count.hpp"

namespace deli {
namespace {

using testing::kThreaded;
using testing::ThreadCount;

// Cluster r's pairs as a scan of every block (in order) for that cluster alone: a block
// touching it, in its numbering with its particle first, and the particle outside it where
// there is one.
std::vector<ShadowOperator::LocalPair> scanned_pairs(const std::vector<const PairHessian*>& blocks,
                                                     const std::vector<std::int32_t>& cluster_of,
                                                     const std::vector<std::int32_t>& local_index,
                                                     std::int32_t r) {
  auto local = [&](std::int32_t g) { return cluster_of[g] == r ? local_index[g] : -1; };
  std::vector<ShadowOperator::LocalPair> pairs;
  for (const PairHessian* block : blocks) {
    std::int32_t a = local(block->a), b = local(block->b), outside = -1;
    if (a < 0 && b < 0) continue;
    if (a < 0) {
      std::swap(a, b);
      outside = block->a;
    } else if (b < 0) {
      outside = block->b;
    }
    pairs.push_back({a, b, outside, block});
  }
  return pairs;
}

TEST(ShadowPairs, AreEachClustersScanOfTheBlocksOnOneThreadAndOnTwo) {
  constexpr std::int32_t kParticles = 800;
  constexpr std::size_t kClusters = 3;
  // Clusters 0, 1 and 2: particles 0-99, 100-179 and 300-340; the others in none.
  std::vector<std::int32_t> cluster_of(kParticles, -1), local_index(kParticles, 0);
  const std::pair<std::int32_t, std::int32_t> spans[kClusters] = {{0, 100}, {100, 180}, {300, 341}};
  for (std::size_t r = 0; r < kClusters; ++r) {
    for (std::int32_t p = spans[r].first; p < spans[r].second; ++p) {
      cluster_of[p] = static_cast<std::int32_t>(r);
      local_index[p] = p - spans[r].first;
    }
  }
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::int32_t> particle(0, kParticles - 1);
  std::vector<PairHessian> blocks;
  while (blocks.size() < 4000) {
    const std::int32_t a = particle(rng), b = particle(rng);
    if (a != b) blocks.push_back({a, b, Eigen::Matrix3d::Zero()});
  }
  // The same blocks as pieces, as the pair terms' chunks leave them: uneven, one empty, the
  // chunks of ShadowPairs' own split falling inside them.
  PairHessianPieces pieces;
  const std::size_t cuts[] = {0, 1300, 1300, 3100, blocks.size()};
  for (std::size_t k = 0; k + 1 < std::size(cuts); ++k) {
    pieces.add().assign(blocks.begin() + static_cast<std::ptrdiff_t>(cuts[k]),
                        blocks.begin() + static_cast<std::ptrdiff_t>(cuts[k + 1]));
  }
  auto check = [&](int threads, bool as_pieces) {
    const ThreadCount count(threads);
    if (threads == 2) ASSERT_GE(chunks_for_cheap(blocks.size()), 2);  // the blocks split
    ShadowPairs made;
    std::vector<const PairHessian*> in_order;
    if (as_pieces) {
      made.make(pieces, cluster_of.data(), local_index.data(), kClusters);
      for (std::size_t k = 0; k < pieces.used; ++k) {
        for (const PairHessian& b : pieces.pieces[k]) in_order.push_back(&b);
      }
    } else {
      made.make(blocks, cluster_of.data(), local_index.data(), kClusters);
      for (const PairHessian& b : blocks) in_order.push_back(&b);
    }
    ASSERT_EQ(in_order.size(), blocks.size());
    std::size_t seen = 0;
    for (std::size_t r = 0; r < kClusters; ++r) {
      const std::vector<ShadowOperator::LocalPair> expected =
          scanned_pairs(in_order, cluster_of, local_index, static_cast<std::int32_t>(r));
      ASSERT_EQ(made.count(r), expected.size()) << "cluster " << r;
      for (std::size_t k = 0; k < expected.size(); ++k) {
        const ShadowOperator::LocalPair& got = made.pairs(r)[k];
        ASSERT_EQ(got.a, expected[k].a) << r << " " << k;
        ASSERT_EQ(got.b, expected[k].b) << r << " " << k;
        ASSERT_EQ(got.outside, expected[k].outside) << r << " " << k;
        ASSERT_EQ(got.block, expected[k].block) << r << " " << k;
      }
      seen += expected.size();
    }
    // Pairs inside a cluster, and of each with outside particles, and with the others.
    EXPECT_GT(seen, 1500u);
  };
  check(1, false);
  check(1, true);
  if (!kThreaded) return;
  check(2, false);
  check(2, true);
}

// A chain of 40 particles 1.2 apart whose first two approach each other in contact, with
// 600 random Hessian blocks among them and 100 with particles outside it: reflect()'s shadow
// products (two: one normal, and the velocities) on two threads, one each, give the momenta
// of one thread bit for bit.
TEST(ShadowPairs, ShadowReflectionOnTwoThreadsIsTheOneThreadReflection) {
  constexpr std::int32_t kChain = 40, kOutside = 100;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal;
  LocalCluster cluster;
  std::vector<Vec3> q, p;
  for (std::int32_t i = 0; i < kChain; ++i) {
    cluster.particles.push_back(i);
    cluster.inverse_mass.push_back(1.0);
    q.push_back({1.2 * i, 0.0, 0.0});
    p.push_back({0.1 * normal(rng), 0.1 * normal(rng), 0.1 * normal(rng)});
  }
  p[0].x = 1.0, p[1].x = -1.0;
  Constraint contact;
  contact.kind = ConstraintKind::sphere_pair;
  contact.i = 0, contact.j = 1, contact.length = 1.2;
  cluster.rows.push_back(contact);
  cluster.global_rows.push_back(0);
  std::vector<Vec3> outside_momenta(kOutside);
  for (Vec3& m : outside_momenta) m = {normal(rng), normal(rng), normal(rng)};
  const std::vector<double> outside_mass(kOutside, 2.0);
  std::vector<PairHessian> hessian;
  std::vector<ShadowOperator::LocalPair> pairs;
  std::vector<std::size_t> block_of_pair;  // pointed to once every block is made
  std::uniform_int_distribution<std::int32_t> bead(0, kChain - 1), other(0, kOutside - 1);
  while (pairs.size() < 700) {
    Eigen::Matrix3d r;
    for (int e = 0; e < 9; ++e) r(e) = normal(rng);
    hessian.push_back({0, 0, 5.0 * (r + r.transpose())});
    const std::int32_t a = bead(rng);
    if (pairs.size() < 600) {
      const std::int32_t b = bead(rng);
      if (b == a) {
        hessian.pop_back();
        continue;
      }
      pairs.push_back({a, b, -1, nullptr});
    } else {
      pairs.push_back({a, -1, other(rng), nullptr});
    }
    block_of_pair.push_back(hessian.size() - 1);
  }
  for (std::size_t k = 0; k < pairs.size(); ++k) pairs[k].block = &hessian[block_of_pair[k]];
  ShadowOperator shadow;
  shadow.h = 0.005;
  shadow.pairs = pairs.data();
  shadow.pair_count = pairs.size();
  shadow.momenta = outside_momenta.data();
  shadow.mass = outside_mass.data();
  const Box box({-100, -100, -100}, {100, 100, 100}, {false, false, false});
  auto reflected = [&](int threads, ReflectionStats& stats) {
    const ThreadCount count(threads);
    std::vector<Vec3> out = p;
    stats = reflect(cluster, {false}, q, out, box, ReflectionOperator::generalized, 1e-10,
                    SolverLimits{}, &shadow);
    return out;
  };
  ReflectionStats one_stats, two_stats;
  const std::vector<Vec3> one = reflected(1, one_stats);
  // The shadow energy's reflection was made (not H's in its place).
  EXPECT_EQ(one_stats.reflected, 1);
  EXPECT_EQ(one_stats.shadow_fallbacks, 0);
  EXPECT_LT(one[0].x, 0.0);  // the pair bounced apart
  if (!kThreaded) return;
  const std::vector<Vec3> two = reflected(2, two_stats);
  EXPECT_EQ(two_stats.iterations, one_stats.iterations);
  for (std::int32_t i = 0; i < kChain; ++i) {
    EXPECT_EQ(two[i].x, one[i].x) << i;
    EXPECT_EQ(two[i].y, one[i].y) << i;
    EXPECT_EQ(two[i].z, one[i].z) << i;
  }
}

}  // namespace
}  // namespace deli
