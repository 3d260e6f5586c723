// The O(rows) projection of inequality normals off chains of rods (F^T W F tridiagonal,
// elimination without pivoting) against a second method, the dense pseudo-inverse the reflection
// took before (N - F (F^T W F)^+ F^T W N by Eigen's complete orthogonal decomposition): the same
// numbers to round-off. Rows that do not form chains are refused and left to that dense path.
#include "solvers/chain_projection.hpp"

#include <gtest/gtest.h>

#include <random>

#include "solvers/cluster_matrices.hpp"

namespace deli {
namespace {

Constraint rod(std::int32_t i, std::int32_t j) {
  Constraint c{ConstraintKind::rod};
  c.i = i, c.j = j, c.length = 1.0;
  return c;
}

// Chains of `beads` particles each (random walks of unit steps, masses in [0.5, 2]), their
// rods numbered along each chain, then `contacts` sphere-pair rows between random particles.
struct Chains {
  LocalCluster local;
  std::vector<Vec3> x;
  std::vector<int> rods, contacts;
};

Chains chains(int count, int beads, int contacts, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> mass(0.5, 2.0);
  Chains c;
  for (int chain = 0; chain < count; ++chain) {
    Vec3 at{normal(rng), normal(rng), normal(rng)};
    for (int b = 0; b < beads; ++b) {
      const auto p = static_cast<std::int32_t>(c.x.size());
      c.x.push_back(at);
      c.local.particles.push_back(p);
      c.local.inverse_mass.push_back(1.0 / mass(rng));
      if (b > 0) {
        c.rods.push_back(static_cast<int>(c.local.rows.size()));
        c.local.rows.push_back(rod(p - 1, p));
      }
      const Vec3 step{normal(rng), normal(rng), normal(rng)};
      at += step * (1.0 / norm(step));
    }
  }
  std::uniform_int_distribution<std::int32_t> any(0, static_cast<std::int32_t>(c.x.size()) - 1);
  for (int k = 0; k < contacts; ++k) {
    Constraint contact{ConstraintKind::sphere_pair};
    contact.i = any(rng);
    do contact.j = any(rng);
    while (contact.j == contact.i);
    contact.length = 0.95;
    c.contacts.push_back(static_cast<int>(c.local.rows.size()));
    c.local.rows.push_back(contact);
  }
  return c;
}

// The dense path: Y = (F^T W F)^+ F^T W N, N - F Y.
void dense(const Chains& c, const Box& box, Eigen::MatrixXd& N, Eigen::MatrixXd& Y) {
  const Eigen::VectorXd w = inverse_mass_diagonal(c.local);
  const Eigen::MatrixXd F = gradient_matrix(c.local, c.rods, c.x, box);
  const Eigen::MatrixXd WF = w.asDiagonal() * F;
  const Eigen::MatrixXd FWF = F.transpose() * WF;
  Y = FWF.completeOrthogonalDecomposition().solve(WF.transpose() * N);
  N -= F * Y;
}

TEST(ChainProjection, SameAsTheDensePseudoInverse) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, false});
  for (const auto& [count, beads, contacts] :
       std::vector<std::array<int, 3>>{{1, 2, 1}, {1, 20, 3}, {3, 20, 4}, {2, 41, 1}}) {
    const Chains c = chains(count, beads, contacts, 100 + count * beads);
    const Eigen::MatrixXd G = gradient_matrix(c.local, c.contacts, c.x, box);
    Eigen::MatrixXd N_fast = G, Y_fast, N_dense = G, Y_dense;
    ASSERT_TRUE(project_out_chains(c.local, c.rods, c.x, box, N_fast, Y_fast));
    dense(c, box, N_dense, Y_dense);
    const double scale = std::max(1.0, N_dense.lpNorm<Eigen::Infinity>());
    EXPECT_LT((N_fast - N_dense).lpNorm<Eigen::Infinity>(), 1e-12 * scale) << beads;
    EXPECT_LT((Y_fast - Y_dense).lpNorm<Eigen::Infinity>(),
              1e-12 * std::max(1.0, Y_dense.lpNorm<Eigen::Infinity>()))
        << beads;
    // The projected normals are W-orthogonal to every rod's gradient.
    const Eigen::MatrixXd F = gradient_matrix(c.local, c.rods, c.x, box);
    const Eigen::MatrixXd along =
        F.transpose() * inverse_mass_diagonal(c.local).asDiagonal() * N_fast;
    EXPECT_LT(along.lpNorm<Eigen::Infinity>(), 1e-12 * scale);
  }
}

TEST(ChainProjection, RefusesRowsThatAreNotChains) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, false});
  Chains c = chains(1, 5, 1, 3);
  const Eigen::MatrixXd G = gradient_matrix(c.local, c.contacts, c.x, box);
  Eigen::MatrixXd N = G, Y;
  // A branch: particle 1 in rods 0, 1 and a third rod 1-3 listed last.
  c.rods.push_back(static_cast<int>(c.local.rows.size()));
  c.local.rows.push_back(rod(1, 3));
  EXPECT_FALSE(project_out_chains(c.local, c.rods, c.x, box, N, Y));
  EXPECT_EQ(N, G);
  // A one-particle equality (a string to an anchor).
  Chains s = chains(1, 3, 1, 4);
  Constraint anchor{ConstraintKind::anchor};
  anchor.i = 0, anchor.length = 1.0;
  s.rods.push_back(static_cast<int>(s.local.rows.size()));
  s.local.rows.push_back(anchor);
  N = gradient_matrix(s.local, s.contacts, s.x, box);
  EXPECT_FALSE(project_out_chains(s.local, s.rods, s.x, box, N, Y));
}

}  // namespace
}  // namespace deli
