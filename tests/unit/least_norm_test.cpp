// LeastNorm (engine/solvers/least_norm.hpp), the least-norm solve of the reflections, the
// momentum projection and the position update where rows are dependent, against a second
// method: the pseudo-inverse from a singular value decomposition (Eigen's JacobiSVD, its small
// singular values dropped), and an LU solve where the matrix is regular. And the reflection's
// dense projection of normals, the one path that solves for a matrix of right-hand sides,
// against its defining property.
#include "solvers/least_norm.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "integrators/reflection.hpp"
#include "solvers/cluster_matrices.hpp"

namespace deli {
namespace {

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) A(r, c) = normal(rng);
  }
  return A;
}

// A^+ b by the singular value decomposition, singular values below `relative` times the
// largest taken as zero. A is square here, where the SVD needs no QR preconditioner: without
// one Eigen's template compiles in a third of the time (a file holding only this SVD: 24 -> 9
// CPU s under the sanitizers at -O0, g++ 12).
Eigen::MatrixXd svd_pseudo_inverse_times(const Eigen::MatrixXd& A, const Eigen::MatrixXd& b,
                                         double relative) {
  if (A.rows() != A.cols()) {
    ADD_FAILURE() << "the reference SVD takes square matrices only";
    return Eigen::MatrixXd::Constant(A.cols(), b.cols(), std::numeric_limits<double>::quiet_NaN());
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd, Eigen::NoQRPreconditioner> svd(
      A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(s.size());
  for (Eigen::Index k = 0; k < s.size(); ++k) {
    if (s(k) > relative * s(0)) inverse(k) = 1.0 / s(k);
  }
  return svd.matrixV() * inverse.asDiagonal() * svd.matrixU().transpose() * b;
}

TEST(LeastNorm, RegularMatrixGivesTheSolution) {
  const Eigen::MatrixXd A = random_matrix(6, 6, 1);
  const Eigen::VectorXd b = random_matrix(6, 1, 2);
  LeastNorm least_norm;
  least_norm.compute(A);
  Eigen::VectorXd x;
  least_norm.solve(b, x);
  const Eigen::VectorXd lu = A.partialPivLu().solve(b);
  EXPECT_LT((x - lu).lpNorm<Eigen::Infinity>(), 1e-12 * lu.lpNorm<Eigen::Infinity>());
  EXPECT_LT((least_norm_solve(A, b) - lu).lpNorm<Eigen::Infinity>(),
            1e-12 * lu.lpNorm<Eigen::Infinity>());
}

// Dependent rows, as a contact repeating a rod gives: rows 3 and 4 copies of rows 0 and 1
// (rank 3 of 5), a right-hand side the rows agree on. The least-norm solution solves the
// system and has no part in A's null space; the SVD's pseudo-inverse gives the same.
TEST(LeastNorm, DependentRowsGiveTheLeastNormSolution) {
  Eigen::MatrixXd A = random_matrix(5, 5, 3);
  A.row(3) = A.row(0);
  A.row(4) = A.row(1);
  const Eigen::VectorXd consistent = A * random_matrix(5, 1, 4);
  const Eigen::VectorXd x = least_norm_solve(A, consistent);
  EXPECT_LT((A * x - consistent).lpNorm<Eigen::Infinity>(), 1e-12);
  const Eigen::MatrixXd svd = svd_pseudo_inverse_times(A, consistent, 1e-12);
  EXPECT_LT((x - svd.col(0)).lpNorm<Eigen::Infinity>(), 1e-12);
}

// The threshold decides what counts as dependent: rows equal but for 1e-14 are one row at the
// position update's threshold (1e-12), two at Eigen's default (about 1e-15 here). With the
// threshold the step stays of the right-hand side's size; without it, it is the exact solve's
// huge one.
TEST(LeastNorm, ThresholdDropsNearlyDependentRows) {
  Eigen::MatrixXd A = random_matrix(4, 4, 5);
  A.row(3) = A.row(2);
  A(3, 0) += 1e-14;
  Eigen::VectorXd b = random_matrix(4, 1, 6);
  b(3) = b(2) + 1e-3;  // the two near copies disagree: the exact solve is about 1e11
  LeastNorm dropped, kept;
  dropped.compute(A, 1e-12);
  kept.compute(A);
  Eigen::VectorXd x_dropped, x_kept;
  dropped.solve(b, x_dropped);
  kept.solve(b, x_kept);
  EXPECT_LT(x_dropped.norm(), 1e3);
  EXPECT_GT(x_kept.norm(), 1e8);
  const Eigen::MatrixXd svd = svd_pseudo_inverse_times(A, b, 1e-12);
  EXPECT_LT((x_dropped - svd.col(0)).lpNorm<Eigen::Infinity>(), 1e-9 * svd.norm());
}

// A matrix of right-hand sides: each column as its own vector solve gives it (to round-off:
// Eigen applies the Householder reflections to a matrix in blocks).
TEST(LeastNorm, EachColumnAsItsVectorSolve) {
  Eigen::MatrixXd A = random_matrix(5, 5, 7);
  A.row(4) = A.row(0) + A.row(1);
  const Eigen::MatrixXd B = A * random_matrix(5, 3, 8);
  Eigen::MatrixXd X;
  least_norm_solve(A, B, X);
  ASSERT_EQ(X.cols(), 3);
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    const Eigen::VectorXd column = B.col(c);
    EXPECT_LT((X.col(c) - least_norm_solve(A, column)).lpNorm<Eigen::Infinity>(), 1e-13) << c;
  }
  EXPECT_LT((A * X - B).lpNorm<Eigen::Infinity>(), 1e-11);
}

// The reflection's normals projected off rows that are not chains (a branched rod cluster,
// which the O(rows) chain projection refuses): the dense path, N = G - F (F^T W F)^+ F^T W G,
// whose columns must be W-orthogonal to every rod's gradient (the impulses leave the rods'
// lengths unchanged to first order) and differ from G by rod gradients alone.
TEST(LeastNorm, BranchedRodsProjectedNormalsAreOrthogonalToTheRods) {
  const Box box({0, 0, 0}, {10, 10, 10}, {false, false, false});
  LocalCluster cluster;
  std::vector<Vec3> x = {{5, 5, 5}, {6, 5, 5}, {6.5, 5.8, 5}, {6.5, 4.2, 5.1}, {5.2, 6, 5.1}};
  for (std::int32_t p = 0; p < 5; ++p) {
    cluster.particles.push_back(p);
    cluster.inverse_mass.push_back(1.0 / (1.0 + 0.25 * p));
  }
  auto row = [&](ConstraintKind kind, std::int32_t i, std::int32_t j) {
    Constraint c{kind};
    c.i = i, c.j = j, c.length = norm(x[i] - x[j]);
    cluster.rows.push_back(c);
  };
  // Particle 1 holds three rods (a branch), plus a contact and a rod repeated as a contact.
  row(ConstraintKind::rod, 0, 1);
  row(ConstraintKind::rod, 1, 2);
  row(ConstraintKind::rod, 1, 3);
  row(ConstraintKind::sphere_pair, 2, 4);
  row(ConstraintKind::sphere_pair, 0, 1);
  const std::vector<bool> equality = {true, true, true, false, false};
  const Eigen::MatrixXd N = projected_normals(cluster, equality, x, box);
  ASSERT_EQ(N.cols(), 2);
  const std::vector<int> rods = {0, 1, 2}, contacts = {3, 4};
  const Eigen::MatrixXd F = gradient_matrix(cluster, rods, x, box);
  const Eigen::MatrixXd G = gradient_matrix(cluster, contacts, x, box);
  const Eigen::VectorXd w = inverse_mass_diagonal(cluster);
  EXPECT_LT((F.transpose() * w.asDiagonal() * N).lpNorm<Eigen::Infinity>(), 1e-12);
  // G - N in the rods' span: its least-squares fit by F's columns leaves nothing. F has full
  // column rank (three independent rods), so the normal equations' Cholesky gives the fit
  // (a QR's template took 13 more CPU s of this file's compile under the sanitizers).
  const Eigen::MatrixXd difference = G - N;
  const Eigen::MatrixXd fit = F * (F.transpose() * F).llt().solve(F.transpose() * difference);
  EXPECT_LT((fit - difference).lpNorm<Eigen::Infinity>(), 1e-12);
  // The repeated rod's contact normal lies along the rod: nothing is left of it.
  EXPECT_LT(N.col(1).lpNorm<Eigen::Infinity>(), 1e-12);
}

}  // namespace
}  // namespace deli
