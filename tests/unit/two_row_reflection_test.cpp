// reflect() takes clusters of two inequality rows (E = H, generalized) in closed form. Against
// the general loop's Lawson-Hanson solves (a second method: reached here through a shadow
// operator without Hessian blocks, whose energy is then H's, K~ = K), on three spheres in a
// chain and on a sphere at a plane touching another: the same momenta, impulses, reflected
// rows and settled flag to rounding, and the kinetic energy kept (analytic).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "constraints/constraint_set.hpp"
#include "integrators/reflection.hpp"

namespace deli {
namespace {

double kinetic_of(const std::vector<Vec3>& p, const std::vector<double>& inverse_mass) {
  double k = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) k += 0.5 * norm2(p[i]) * inverse_mass[i];
  return k;
}

struct TwoRowCase {
  LocalCluster cluster;
  std::vector<Vec3> x, p;
};

// Spheres 0-1-2 (diameter 1) touching along random directions, or sphere 0 at a plane and
// touching sphere 1; random masses and momenta.
TwoRowCase random_case(std::mt19937_64& rng, bool wall) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto direction = [&] {
    Vec3 d{normal(rng), normal(rng), normal(rng)};
    return d * (1.0 / norm(d));
  };
  TwoRowCase c;
  const int particles = wall ? 2 : 3;
  c.x.push_back({5.0, 5.0, 5.0});
  for (int k = 1; k < particles; ++k) c.x.push_back(c.x.back() + direction());
  for (int k = 0; k < particles; ++k) {
    c.cluster.particles.push_back(k);
    c.cluster.inverse_mass.push_back(1.0 / (0.5 + 1.5 * unit(rng)));
    c.p.push_back(Vec3{normal(rng), normal(rng), normal(rng)} * 2.0);
  }
  Constraint pair;
  pair.kind = ConstraintKind::sphere_pair;
  pair.length = 1.0;
  pair.i = 0, pair.j = 1;
  c.cluster.rows.push_back(pair);
  if (wall) {
    Constraint plane;
    plane.kind = ConstraintKind::plane;
    plane.i = 0;
    plane.normal = direction();
    plane.point = c.x[0] - plane.normal * 0.5;
    plane.length = 0.5;
    c.cluster.rows.push_back(plane);
  } else {
    pair.i = 1, pair.j = 2;
    c.cluster.rows.push_back(pair);
  }
  c.cluster.global_rows = {0, 1};
  return c;
}

TEST(TwoRowReflection, AgreesWithTheGeneralLoop) {
  const Box box({0, 0, 0}, {10, 10, 10}, {true, true, true});
  const double tolerance = 1e-10;
  const std::vector<bool> inequalities = {false, false};
  std::mt19937_64 rng(21);
  int both = 0, one = 0;
  for (const bool wall : {false, true}) {
    for (int trial = 0; trial < 400; ++trial) {
      SCOPED_TRACE(::testing::Message() << "wall " << wall << " trial " << trial);
      const TwoRowCase c = random_case(rng, wall);
      std::vector<Vec3> closed = c.p, general = c.p;
      const ReflectionStats a = reflect(c.cluster, inequalities, c.x, closed, box,
                                        ReflectionOperator::generalized, tolerance, SolverLimits{});
      ShadowOperator without_blocks;  // no pair blocks: K~ = K
      without_blocks.h = 0.005;
      const ReflectionStats b =
          reflect(c.cluster, inequalities, c.x, general, box, ReflectionOperator::generalized,
                  tolerance, SolverLimits{}, &without_blocks);
      ASSERT_EQ(b.shadow_fallbacks, 0);
      EXPECT_EQ(a.reflected, b.reflected);
      EXPECT_EQ(a.settled, b.settled);
      EXPECT_EQ(a.capped, b.capped);
      double scale = 1.0;
      for (const Vec3& v : c.p) scale = std::max(scale, norm(v));
      for (std::size_t k = 0; k < closed.size(); ++k) {
        EXPECT_LT(norm(closed[k] - general[k]), 1e-12 * scale);
      }
      for (std::size_t r = 0; r < 2; ++r) {
        EXPECT_NEAR(a.row_impulse[r], b.row_impulse[r], 1e-12 * scale);
      }
      const double before = kinetic_of(c.p, c.cluster.inverse_mass);
      EXPECT_NEAR(kinetic_of(closed, c.cluster.inverse_mass), before, 1e-12 * before);
      both += a.row_impulse[0] > 0.0 && a.row_impulse[1] > 0.0 ? 1 : 0;
      one += (a.row_impulse[0] > 0.0) != (a.row_impulse[1] > 0.0) ? 1 : 0;
    }
  }
  // Both kinds of solution met: both rows pushing, and one alone.
  EXPECT_GT(both, 20);
  EXPECT_GT(one, 20);
}

}  // namespace
}  // namespace deli
