// The constraint solvers and the cluster finding on small problems whose answers are known
// analytically: a dependent pair of normals, a degenerate QP vertex, a rigid rod loop
// (dependent rows) and one with a redundant rod, a contact plus a rod, a contact plus a
// string that repeat each other at
// the start of the step, and a cluster that merges and splits as a contact comes and goes.
// Each test states where its expected value comes from.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "constraints/clusters.hpp"
#include "constraints/constraint_set.hpp"
#include "integrators/reflection.hpp"
#include "solvers/momentum_update.hpp"
#include "solvers/nonnegative_qp.hpp"
#include "solvers/position_update.hpp"
#include "solvers/prepared_clusters.hpp"

namespace deli {
namespace {

const Box kOpenBox({-10, -10, -10}, {10, 10, 10}, {false, false, false});
const SolverLimits kLimits;  // the run's defaults

Constraint rod(std::int32_t i, std::int32_t j, double length) {
  Constraint c;
  c.kind = ConstraintKind::rod;
  c.i = i;
  c.j = j;
  c.length = length;
  return c;
}

// A floor z = height for a point particle (radius 0).
Constraint floor_at(std::int32_t i, double height) {
  Constraint c;
  c.kind = ConstraintKind::plane;
  c.i = i;
  c.point = {0, 0, height};
  c.normal = {0, 0, 1};
  return c;
}

// `count` tries at a random row among n particles, draw k = count..1: a floor under a random
// particle where k is a multiple of `wall_every`, else a sphere pair of two random particles
// (of particles i and i + 2 where k is a multiple of `near_every`, if not 0), dropped where
// it would join a particle to itself or reach past n.
void append_random_contacts(std::vector<Constraint>& rows, std::mt19937_64& rng, std::size_t n,
                            int count, int wall_every, int near_every) {
  std::uniform_int_distribution<std::int32_t> particle(0, static_cast<std::int32_t>(n) - 1);
  for (int k = count; k > 0; --k) {
    if (k % wall_every == 0) {
      rows.push_back(floor_at(particle(rng), 0.0));
      continue;
    }
    Constraint contact;
    contact.kind = ConstraintKind::sphere_pair;
    contact.i = particle(rng);
    contact.j = near_every > 0 && k % near_every == 0 ? contact.i + 2 : particle(rng);
    if (contact.j >= static_cast<std::int32_t>(n) || contact.j == contact.i) continue;
    contact.length = 1.0;
    rows.push_back(contact);
  }
}

LocalCluster cluster_of(const std::vector<double>& masses, const std::vector<Constraint>& rows) {
  LocalCluster cluster;
  for (std::size_t k = 0; k < masses.size(); ++k) {
    cluster.particles.push_back(static_cast<std::int32_t>(k));
    cluster.inverse_mass.push_back(1.0 / masses[k]);
  }
  cluster.rows = rows;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    cluster.global_rows.push_back(static_cast<std::int32_t>(r));
  }
  return cluster;
}

void expect_vec_near(const Vec3& a, const Vec3& b, double tolerance) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

// --- Non-negative QP -------------------------------------------------------------------

// Two identical normals n (a sphere on a floor listed twice), unit mass, K = M^-1 / 2:
// Q = N^T K N = [[1/2, 1/2], [1/2, 1/2]] (singular), c = 2 N^T K p = (p.n, p.n). With
// p.n = -1 the minimisers are the segment x1 + x2 = 2, x >= 0 (dQ/dx = (x1 + x2)/2 - 1 = 0).
TEST(NonnegativeQp, DependentPairOfNormals) {
  Eigen::MatrixXd Q(2, 2);
  Q << 0.5, 0.5, 0.5, 0.5;
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(2, -1.0);
  Eigen::VectorXd x;
  const SolverStatus status = solve_nonnegative_qp(Q, c, x, 1e-14);
  EXPECT_TRUE(status.converged);
  EXPECT_LE(status.residual, 1e-14);
  EXPECT_GE(x.minCoeff(), 0.0);
  EXPECT_NEAR(x.sum(), 2.0, 1e-14);
}

// A degenerate vertex: Q = I, c = (0, -1). The minimiser is x = (0, 1) (x2 = -c2; x1 = 0
// with gradient 0 there: both x1 = 0 and (Qx + c)_1 = 0, the degenerate case that makes
// active-set methods cycle).
TEST(NonnegativeQp, DegenerateVertex) {
  const Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(2, 2);
  Eigen::VectorXd c(2);
  c << 0.0, -1.0;
  Eigen::VectorXd x;
  const SolverStatus status = solve_nonnegative_qp(Q, c, x, 1e-14);
  EXPECT_TRUE(status.converged);
  EXPECT_EQ(x(0), 0.0);
  EXPECT_EQ(x(1), 1.0);
}

// A corner of two walls (normals x and y) with a third, redundant wall at 45 degrees
// through the same corner: the cone of the three normals is the quadrant of the first two,
// so min |N lambda + 2p| over lambda >= 0 is 0 at N lambda = -2p for p = (-1, -1, .):
// lambda is not unique (a degenerate vertex of a rank-2 Q in three variables), N lambda is.
TEST(NonnegativeQp, RedundantWallAtACorner) {
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(3, 3);
  N(0, 0) = 1.0;
  N(1, 1) = 1.0;
  N(0, 2) = N(1, 2) = std::sqrt(0.5);
  const Eigen::Vector3d p(-1.0, -1.0, 0.5);
  const Eigen::MatrixXd Q = 0.5 * N.transpose() * N;
  const Eigen::VectorXd c = N.transpose() * p;  // 2 N^T K p with K = I/2
  Eigen::VectorXd lambda;
  const SolverStatus status = solve_nonnegative_qp(Q, c, lambda, 1e-14);
  EXPECT_TRUE(status.converged);
  EXPECT_GE(lambda.minCoeff(), 0.0);
  const Eigen::Vector3d reflected = p + N * lambda;
  EXPECT_NEAR(reflected(0), 1.0, 1e-14);
  EXPECT_NEAR(reflected(1), 1.0, 1e-14);
  EXPECT_EQ(reflected(2), 0.5);
}

// An iteration cap too small to finish is reported: not converged, with the residual of
// the unfinished iterate (here x = 0: the largest negative gradient, 1).
TEST(NonnegativeQp, CapHitIsReported) {
  const Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(3, -1.0);
  Eigen::VectorXd x;
  const SolverStatus capped = solve_nonnegative_qp(Q, c, x, 1e-14, 1);
  EXPECT_FALSE(capped.converged);
  EXPECT_GT(capped.residual, 0.5);
  const SolverStatus full = solve_nonnegative_qp(Q, c, x, 1e-14);
  EXPECT_TRUE(full.converged);
  EXPECT_EQ(x, Eigen::VectorXd::Constant(3, 1.0));  // x = -Q^-1 c
}

// --- Reflection -------------------------------------------------------------------------

// An elastic bounce off a floor listed twice (dependent normals): the normal velocity is
// reversed and the tangential one kept, as for a single floor (energy and the tangential
// momentum conserved, the contact non-approaching: the only such impulse along z).
TEST(Reflection, DependentPairOfNormalsBouncesOnce) {
  const LocalCluster cluster = cluster_of({2.0}, {floor_at(0, 0.0), floor_at(0, 0.0)});
  std::vector<Vec3> p{{0.6, -0.2, -2.0}};
  const ReflectionStats stats = reflect(cluster, {false, false}, {{0.3, 0.1, 0.0}}, p, kOpenBox,
                                        ReflectionOperator::generalized, 1e-10, kLimits);
  EXPECT_FALSE(stats.capped);
  EXPECT_FALSE(stats.cycled);
  expect_vec_near(p[0], {0.6, -0.2, 2.0}, 1e-14);
}

// reflect() and the QP keep their vectors and decompositions between calls: a call after
// others of other sizes gives the same bits as the first (the expected values are that first
// call's: same input, same result). A corner of two walls, the floor listed twice (three
// rows, one particle), then two particles on the floor (two rows), then the corner again.
TEST(Reflection, KeptScratchCarriesNothingToTheNextCall) {
  Constraint wall = floor_at(0, 0.0);
  wall.normal = {1, 0, 0};
  const LocalCluster corner = cluster_of({2.0}, {floor_at(0, 0.0), wall, floor_at(0, 0.0)});
  const LocalCluster pair = cluster_of({1.0, 3.0}, {floor_at(0, 0.0), floor_at(1, 0.0)});
  auto bounce_corner = [&](std::vector<Vec3>& p) {
    return reflect(corner, {false, false, false}, {{0.0, 0.1, 0.0}}, p, kOpenBox,
                   ReflectionOperator::generalized, 1e-10, kLimits);
  };
  std::vector<Vec3> first{{-0.7, 0.3, -1.1}};
  const ReflectionStats first_stats = bounce_corner(first);
  std::vector<Vec3> p_pair{{0.2, 0.0, -0.5}, {0.0, 0.4, -0.9}};
  (void)reflect(pair, {false, false}, {{0, 0, 0}, {1, 0, 0}}, p_pair, kOpenBox,
                ReflectionOperator::generalized, 1e-10, kLimits);
  std::vector<Vec3> again{{-0.7, 0.3, -1.1}};
  const ReflectionStats again_stats = bounce_corner(again);
  EXPECT_EQ(again[0].x, first[0].x);
  EXPECT_EQ(again[0].y, first[0].y);
  EXPECT_EQ(again[0].z, first[0].z);
  EXPECT_EQ(again_stats.row_impulse, first_stats.row_impulse);
  EXPECT_EQ(again_stats.iterations, first_stats.iterations);
  expect_vec_near(first[0], {0.7, 0.3, 1.1}, 1e-14);  // both normal components reversed
}

// --- Momentum update --------------------------------------------------------------------

// A flat square with its four sides and both diagonals as rods: six rows on four particles
// whose gradients all lie in the plane, rank 5 (the out-of-plane velocities of all four
// corners are free to first order: 12 - 7 = 5), so the constraint matrix is singular. The
// projection keeps the impulses internal and central: the in-plane velocities become the
// rigid motion with the same linear and angular momentum (V = P / M, omega = L_z / I_z about
// the centre of mass), and the out-of-plane velocities are untouched.
TEST(MomentumUpdate, RigidRodLoopWithDependentRows) {
  const std::vector<double> masses{1.0, 2.0, 1.5, 0.5};
  const std::vector<Vec3> x{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const double diagonal = std::sqrt(2.0);
  const LocalCluster cluster =
      cluster_of(masses, {rod(0, 1, 1), rod(1, 2, 1), rod(2, 3, 1), rod(3, 0, 1),
                          rod(0, 2, diagonal), rod(1, 3, diagonal)});
  std::vector<Vec3> p{{0.3, -1.0, 0.2}, {1.1, 0.4, -0.7}, {-0.5, 0.9, 0.3}, {0.2, 0.2, 1.0}};
  // Expected: rigid in-plane motion with the same momentum and angular momentum.
  double mass = 0, inertia = 0, angular = 0;
  Vec3 momentum{}, centre{};
  for (std::size_t k = 0; k < 4; ++k) {
    mass += masses[k];
    momentum += p[k];
    centre += x[k] * masses[k];
  }
  centre = centre * (1.0 / mass);
  for (std::size_t k = 0; k < 4; ++k) {
    const Vec3 r = x[k] - centre;
    inertia += masses[k] * (r.x * r.x + r.y * r.y);
    angular += r.x * p[k].y - r.y * p[k].x;
  }
  const double omega = angular / inertia;
  std::vector<Vec3> expected(4);
  for (std::size_t k = 0; k < 4; ++k) {
    const Vec3 r = x[k] - centre;
    expected[k] = {momentum.x / mass - omega * r.y, momentum.y / mass + omega * r.x,
                   p[k].z / masses[k]};
  }
  Eigen::VectorXd mu;
  const SolverStatus status =
      project_momentum(cluster, {0, 1, 2, 3, 4, 5}, x, p, kOpenBox, 1e-12, mu);
  EXPECT_TRUE(status.converged);
  EXPECT_LE(status.residual, 1e-12);
  for (std::size_t k = 0; k < 4; ++k) expect_vec_near(p[k] * (1.0 / masses[k]), expected[k], 1e-13);
}

// A projection whose residual stays above the tolerance is reported, never passed off as
// converged because its multipliers are finite: the dependent rods of the flat square leave
// a rounding-level residual (about 1e-16), above a tolerance of 1e-300 and below 1e-12.
TEST(MomentumUpdate, ResidualAboveToleranceIsNotConverged) {
  const std::vector<Vec3> x{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const double diagonal = std::sqrt(2.0);
  const LocalCluster cluster =
      cluster_of({1.0, 2.0, 1.5, 0.5}, {rod(0, 1, 1), rod(1, 2, 1), rod(2, 3, 1), rod(3, 0, 1),
                                        rod(0, 2, diagonal), rod(1, 3, diagonal)});
  const std::vector<Vec3> p0{{0.3, -1.0, 0.2}, {1.1, 0.4, -0.7}, {-0.5, 0.9, 0.3}, {0.2, 0.2, 1.0}};
  Eigen::VectorXd mu;
  std::vector<Vec3> p = p0;
  const SolverStatus strict =
      project_momentum(cluster, {0, 1, 2, 3, 4, 5}, x, p, kOpenBox, 1e-300, mu);
  EXPECT_FALSE(strict.converged);
  EXPECT_TRUE(mu.allFinite());
  EXPECT_GT(strict.residual, 1e-300);
  EXPECT_LT(strict.residual, 1e-12);
  p = p0;
  const SolverStatus loose =
      project_momentum(cluster, {0, 1, 2, 3, 4, 5}, x, p, kOpenBox, 1e-12, mu);
  EXPECT_TRUE(loose.converged);
}

// --- Position update --------------------------------------------------------------------

// A vertical dimer standing on a floor (bottom particle 0 at z = 0 touching it, particle 1
// at z = 1, rod of length 1) and a step that would move both down by d: both stay where
// they are. Gap of the floor: -d + h/m (z_c - z_rod) = 0; rod: -d + h/m z_rod = 0, so
// z_rod = m d / h (the rod holds the top particle) and z_c = 2 m d / h (the floor holds
// both).
TEST(PositionUpdate, ContactPlusRod) {
  const double m = 1.5, h = 0.01, d = 2e-3;
  const LocalCluster cluster = cluster_of({m, m}, {rod(0, 1, 1.0), floor_at(0, 0.0)});
  const std::vector<Vec3> q{{0.2, 0.1, 0.0}, {0.2, 0.1, 1.0}};
  const std::vector<Vec3> x0{{0.2, 0.1, -d}, {0.2, 0.1, 1.0 - d}};
  const PositionUpdate solved = solve_position_update(cluster, {true, false}, q, x0, h, kOpenBox,
                                                      1e-12, kLimits.newton, kLimits.line_search);
  ASSERT_TRUE(solved.status.converged) << solved.status.residual;
  EXPECT_NEAR(solved.z(0), m * d / h, 1e-10);
  EXPECT_NEAR(solved.z(1), 2 * m * d / h, 1e-10);
  expect_vec_near(solved.x[0], q[0], 1e-12);
  expect_vec_near(solved.x[1], q[1], 1e-12);
}

// A bob hanging from a string (anchor at height L straight above it) that also rests on a
// floor: both rows push along z at the start of the step, so the Newton matrix built with
// the gradients at q is singular (the rows repeat each other). A step moving the bob
// sideways by a and down by d ends on the string's sphere, which lies above the floor
// there: x = (a, 0, L - sqrt(L^2 - a^2)) (only a z impulse is possible: the gradients at q
// point along z), the floor's impulse 0 (complementarity: it no longer touches).
TEST(PositionUpdate, ContactPlusStringRepeatingEachOther) {
  const double L = 1.0, a = 0.05, d = 1e-3, h = 0.01;
  Constraint string;
  string.kind = ConstraintKind::anchor;
  string.i = 0;
  string.point = {0, 0, L};
  string.length = L;
  const LocalCluster cluster = cluster_of({1.0}, {string, floor_at(0, 0.0)});
  const std::vector<Vec3> q{{0, 0, 0}};
  const std::vector<Vec3> x0{{a, 0, -d}};
  const PositionUpdate solved = solve_position_update(cluster, {true, false}, q, x0, h, kOpenBox,
                                                      1e-12, kLimits.newton, kLimits.line_search);
  ASSERT_TRUE(solved.status.converged) << solved.status.residual;
  expect_vec_near(solved.x[0], {a, 0, L - std::sqrt(L * L - a * a)}, 1e-12);
  EXPECT_NEAR(solved.z(1), 0.0, 1e-10);
}

// A triangular bipyramid held by all ten of its distances: five atoms, nine independent rods
// and a redundant tenth (a rigid loop; rank 9, yet infinitesimally rigid: only rigid
// motions are free). A step of rigid velocities (translation plus rotation, to first order)
// is feasible, but the Newton matrix is exactly singular: LU took huge finite steps along
// its null direction (the run of tests/solver_problems/rigid_bipyramid_redundant_rod.txt
// stopped at its first step). Expected: every rod held to the tolerance, and impulses that
// are internal and central (along the rods at q): total impulse and its torque zero
// (Newton's third law), with multipliers of the size the step needs, not huge.
TEST(PositionUpdate, RigidLoopWithARedundantRod) {
  const double s3 = std::sqrt(3.0);
  const std::vector<Vec3> q{
      {1, 0, 0}, {-0.5, s3 / 2, 0}, {-0.5, -s3 / 2, 0}, {0, 0, 1}, {0, 0, -1}};
  const std::vector<double> masses{1.0, 2.0, 1.5, 0.5, 1.0};
  std::vector<Constraint> rows;
  const std::pair<int, int> pairs[] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 1},
                                       {3, 2}, {4, 0}, {4, 1}, {4, 2}, {3, 4}};
  for (const auto& [i, j] : pairs) {
    rows.push_back(rod(i, j, norm(q[i] - q[j])));
  }
  const LocalCluster cluster = cluster_of(masses, rows);
  const double h = 0.005;
  const Vec3 velocity{0.3, -1.0, 0.2}, omega{1.1, 0.4, -0.7};
  std::vector<Vec3> x0(q.size());
  for (std::size_t k = 0; k < q.size(); ++k) x0[k] = q[k] + (velocity + cross(omega, q[k])) * h;
  const PositionUpdate solved =
      solve_position_update(cluster, std::vector<bool>(rows.size(), true), q, x0, h, kOpenBox,
                            1e-12, kLimits.newton, kLimits.line_search);
  ASSERT_TRUE(solved.status.converged) << solved.status.residual;
  for (const Constraint& c : cluster.rows) {
    EXPECT_NEAR(norm(solved.x[c.i] - solved.x[c.j]), c.length, 1e-12);
  }
  Vec3 total{}, torque{};
  for (std::size_t k = 0; k < q.size(); ++k) {
    total += solved.impulse[k];
    torque += cross(q[k], solved.impulse[k]);
  }
  EXPECT_LT(norm(total), 1e-12);
  EXPECT_LT(norm(torque), 1e-12);
  // The rotation's second-order error is |omega|^2 h^2 r ~ 4e-5: impulses of that order / h.
  EXPECT_LT(solved.z.lpNorm<Eigen::Infinity>(), 1e-1);
}

// --- Clusters ---------------------------------------------------------------------------

// Two rod chains (0-1-2 and 3-4) and a wall under particle 4: two clusters, the wall's row
// in the second. A contact between 2 and 3 merges them into one cluster holding every row;
// when it goes the cluster splits back and the prepared (equality) clusters are found
// again; the merged cluster has no prepared form. Expected by hand from the rows.
TEST(Clusters, MergeAndSplit) {
  const std::vector<Constraint> rods{rod(0, 1, 1), rod(1, 2, 1), rod(3, 4, 1)};
  Constraint contact;
  contact.kind = ConstraintKind::sphere_pair;
  contact.i = 3;
  contact.j = 2;
  contact.length = 1.0;
  std::vector<Constraint> apart = rods;
  apart.push_back(floor_at(4, 0.0));
  std::vector<Constraint> touching = apart;
  touching.push_back(contact);
  const std::size_t n = 6;  // particle 5 touches nothing: in no cluster

  const std::vector<Cluster> two = find_clusters(apart, n);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0].particles, (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(two[0].rows, (std::vector<std::int32_t>{0, 1}));
  EXPECT_EQ(two[1].particles, (std::vector<std::int32_t>{3, 4}));
  EXPECT_EQ(two[1].rows, (std::vector<std::int32_t>{2, 3}));

  const std::vector<Cluster> merged = find_clusters(touching, n);
  ASSERT_EQ(merged.size(), 1u);
  EXPECT_EQ(merged[0].particles, (std::vector<std::int32_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(merged[0].rows, (std::vector<std::int32_t>{0, 1, 2, 3, 4}));
  const LocalCluster local = localize(merged[0], touching, std::vector<double>(n, 1.0));
  EXPECT_EQ(local.rows[4].i, 3);  // global 3 is local 3: particles 0..4 in order
  EXPECT_EQ(local.rows[4].j, 2);

  const std::vector<double> masses(n, 1.0);
  EqualityClusters prepared;
  prepared.prepare(rods, masses);
  ASSERT_EQ(prepared.all().size(), 2u);
  EXPECT_EQ(prepared.find(merged[0], touching), nullptr);
  // Split again (the contact gone, the rods alone): each chain is its prepared cluster.
  const std::vector<Cluster> split = find_clusters(rods, n);
  ASSERT_EQ(split.size(), 2u);
  EXPECT_EQ(prepared.find(split[0], rods), &prepared.all()[0]);
  EXPECT_EQ(prepared.find(split[1], rods), &prepared.all()[1]);
  // The second chain with the wall is not the prepared one (an extra row).
  EXPECT_EQ(prepared.find(two[1], apart), nullptr);
  EXPECT_EQ(prepared.find(two[0], apart), &prepared.all()[0]);
}

// EqualityClusters::clusters_holding against its definition, find_clusters of every row with
// the clusters of rods alone dropped: the same clusters, particles and rows, in the same order.
// 30 rod chains of 2-9 beads among 200 particles (the rest in no chain; in every other trial
// the particles shuffled, so that chains interleave), with random pair and wall rows after
// the rods: pairs within a chain, between chains, between free particles, and several rows on
// one particle.
TEST(Clusters, HoldingOtherRowsAreFindClustersWithoutTheRodsAlone) {
  const std::size_t n = 200;
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Constraint> rods;
    std::uniform_int_distribution<int> length(2, 9);
    std::int32_t next = 0;
    for (int chain = 0; chain < 30 && next < 190; ++chain) {
      next += length(rng) % 3;  // some particles between chains are in none
      const std::int32_t beads = length(rng);
      for (std::int32_t b = 1; b < beads && next + b < static_cast<std::int32_t>(n); ++b) {
        rods.push_back(rod(next + b - 1, next + b, 1.0));
      }
      next += beads;
    }
    // Chains over particles in no order (as a data file may number them).
    std::vector<std::int32_t> label(n);
    std::iota(label.begin(), label.end(), 0);
    if (trial % 2) std::shuffle(label.begin(), label.end(), rng);
    for (Constraint& r : rods) r.i = label[r.i], r.j = label[r.j];
    EqualityClusters prepared;
    prepared.prepare(rods, std::vector<double>(n, 1.0));
    std::vector<Constraint> rows = rods;
    std::uniform_int_distribution<int> others(0, 12);
    // Every fifth pair within two indices: often within a chain.
    append_random_contacts(rows, rng, n, others(rng), 4, 5);
    std::vector<Cluster> expected;
    for (Cluster& cluster : find_clusters(rows, n)) {
      if (cluster.rows.back() >= static_cast<std::int32_t>(rods.size())) {
        expected.push_back(std::move(cluster));
      }
    }
    const std::vector<Cluster> holding = prepared.clusters_holding(rows, rods.size());
    ASSERT_EQ(holding.size(), expected.size()) << "trial " << trial;
    for (std::size_t c = 0; c < expected.size(); ++c) {
      EXPECT_EQ(holding[c].particles, expected[c].particles)
          << "trial " << trial << " cluster " << c;
      EXPECT_EQ(holding[c].rows, expected[c].rows) << "trial " << trial << " cluster " << c;
    }
  }
  EqualityClusters prepared;
  prepared.prepare({rod(0, 1, 1.0)}, std::vector<double>(3, 1.0));
  EXPECT_THROW(prepared.clusters_holding({rod(0, 1, 1.0), floor_at(2, 0.0)}, 0), std::logic_error);
}

// find_clusters and localize into storage kept from earlier calls (the reflections' scratch)
// against the same calls into fresh objects: the same clusters and local clusters whatever
// the kept objects held, over random contact sets of 1-40 rows among 60 particles, whose
// cluster counts and sizes rise and fall from one call to the next.
TEST(Clusters, IntoKeptStorageAreTheClustersOfFreshOnes) {
  const std::size_t n = 60;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> row_count(1, 40);
  std::vector<double> mass(n);
  for (std::size_t i = 0; i < n; ++i) mass[i] = 1.0 + static_cast<double>(i % 7);
  std::vector<Cluster> kept;
  LocalCluster kept_local;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<Constraint> rows;
    append_random_contacts(rows, rng, n, row_count(rng), 6, 0);
    const std::vector<Cluster> fresh = find_clusters(rows, n);
    find_clusters(rows, n, kept);
    ASSERT_EQ(kept.size(), fresh.size()) << "trial " << trial;
    for (std::size_t c = 0; c < fresh.size(); ++c) {
      EXPECT_EQ(kept[c].particles, fresh[c].particles) << "trial " << trial << " cluster " << c;
      EXPECT_EQ(kept[c].rows, fresh[c].rows) << "trial " << trial << " cluster " << c;
      const LocalCluster local = localize(fresh[c], rows, mass);
      localize(kept[c], rows, mass, kept_local);
      EXPECT_EQ(kept_local.particles, local.particles) << "trial " << trial;
      EXPECT_EQ(kept_local.global_rows, local.global_rows) << "trial " << trial;
      EXPECT_EQ(kept_local.inverse_mass, local.inverse_mass) << "trial " << trial;
      ASSERT_EQ(kept_local.rows.size(), local.rows.size()) << "trial " << trial;
      for (std::size_t r = 0; r < local.rows.size(); ++r) {
        EXPECT_EQ(kept_local.rows[r].i, local.rows[r].i) << "trial " << trial;
        EXPECT_EQ(kept_local.rows[r].j, local.rows[r].j) << "trial " << trial;
      }
    }
  }
}

}  // namespace
}  // namespace deli
