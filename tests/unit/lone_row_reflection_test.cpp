// The closed-form reflection of a lone contact gives reflect()'s momenta (the generic dense
// QP path, generalized operator, E = H) up to rounding, keeps the kinetic energy and total
// momentum, reverses the normal velocity, and leaves a row that is not approaching
// untouched: hard-sphere pairs across a periodic boundary with unequal masses, and one
// particle at a plane and inside a sphere.
#include "integrators/lone_row_reflection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "constraints/constraint_set.hpp"
#include "integrators/reflection.hpp"

namespace deli {
namespace {

double kinetic(const std::vector<Vec3>& p, const std::vector<double>& mass) {
  double k = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) k += 0.5 * norm2(p[i]) / mass[i];
  return k;
}

// The row in a one-row cluster of its own particles, for reflect().
LocalCluster lone_cluster(const Constraint& row, const std::vector<double>& mass) {
  LocalCluster local;
  Constraint c = row;
  local.particles.push_back(row.i);
  local.inverse_mass.push_back(1.0 / mass[row.i]);
  c.i = 0;
  if (row.j >= 0) {
    local.particles.push_back(row.j);
    local.inverse_mass.push_back(1.0 / mass[row.j]);
    c.j = 1;
  }
  local.rows.push_back(c);
  local.global_rows.push_back(0);
  return local;
}

struct Outcome {
  std::vector<Vec3> p;
  double impulse;
  int reflected;
};

Outcome generic(const Constraint& row, const std::vector<Vec3>& x, std::vector<Vec3> p,
                const std::vector<double>& mass, const Box& box, double tolerance) {
  const LocalCluster local = lone_cluster(row, mass);
  std::vector<Vec3> x_local, p_local;
  for (std::int32_t g : local.particles) x_local.push_back(x[g]), p_local.push_back(p[g]);
  const ReflectionStats stats = reflect(local, {false}, x_local, p_local, box,
                                        ReflectionOperator::generalized, tolerance, SolverLimits{});
  for (std::size_t k = 0; k < local.particles.size(); ++k) p[local.particles[k]] = p_local[k];
  return {p, stats.row_impulse[0], stats.reflected};
}

void expect_close(const Vec3& a, const Vec3& b, double scale) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-14 * scale);
}

TEST(LoneRowReflection, SpherePairsAgreeWithTheGenericReflection) {
  const Box box({0, 0, 0}, {5, 6, 7}, {true, true, true});
  const double tolerance = 1e-10;
  std::mt19937_64 rng(12);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int approaching = 0;
  for (int trial = 0; trial < 200; ++trial) {
    // Particle 0 near the upper x face, particle 1 across it (through the periodic image).
    std::vector<Vec3> x = {{4.7 + 0.2 * unit(rng), 3.0, 3.0}, {}};
    Vec3 d{normal(rng), normal(rng), normal(rng)};
    d = d * (1.0 / norm(d));
    x[1] = x[0] + d;
    std::array<int, 3> image{};
    box.wrap(x[1], image);
    const std::vector<double> mass = {0.5 + 1.5 * unit(rng), 0.5 + 1.5 * unit(rng)};
    const std::vector<Vec3> p = {{normal(rng), normal(rng), normal(rng)},
                                 {normal(rng), normal(rng), normal(rng)}};
    Constraint row;
    row.kind = ConstraintKind::sphere_pair;
    row.i = 0, row.j = 1, row.length = 1.0;
    const Outcome expected = generic(row, x, p, mass, box, tolerance);
    std::vector<Vec3> lean = p;
    const double lambda = reflect_lone_row(row, x.data(), box, mass, tolerance, lean.data());
    ASSERT_GE(lambda, 0.0);
    EXPECT_EQ(lambda > 0.0 ? 1 : 0, expected.reflected);
    EXPECT_NEAR(lambda, expected.impulse, 1e-14 * std::max(1.0, std::abs(lambda)));
    const double scale = std::max(1.0, std::abs(lambda));
    for (int k = 0; k < 2; ++k) expect_close(lean[k], expected.p[k], scale);
    // Total momentum and kinetic energy kept (analytic: an elastic collision).
    expect_close(lean[0] + lean[1], p[0] + p[1], scale);
    EXPECT_NEAR(kinetic(lean, mass), kinetic(p, mass), 1e-13 * kinetic(p, mass));
    if (lambda > 0.0) {
      ++approaching;
      const Vec3 u = evaluate(row, x.data(), box).u;
      const double before = dot(u, p[0]) / mass[0] - dot(u, p[1]) / mass[1];
      const double after = dot(u, lean[0]) / mass[0] - dot(u, lean[1]) / mass[1];
      EXPECT_NEAR(after, -before, 1e-13 * std::abs(before));
    } else {
      EXPECT_EQ(lean[0].x, p[0].x);  // not approaching: untouched, bit for bit
      EXPECT_EQ(lean[1].z, p[1].z);
    }
  }
  EXPECT_GT(approaching, 50);  // both branches met
  EXPECT_LT(approaching, 150);
}

TEST(LoneRowReflection, WallsAgreeWithTheGenericReflection) {
  const Box box({0, 0, 0}, {10, 10, 10}, {true, true, false});
  const double tolerance = 1e-10;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  for (ConstraintKind kind : {ConstraintKind::plane, ConstraintKind::inside_sphere}) {
    for (int trial = 0; trial < 100; ++trial) {
      Constraint row;
      row.kind = kind;
      row.i = 0;
      if (kind == ConstraintKind::plane) {
        row.point = {0, 0, 0};
        row.normal = {0, 0, 1};
        row.length = 0.5;
      } else {
        row.point = {5, 5, 5};
        row.length = 3.0 - 0.5;
      }
      const std::vector<Vec3> x = {kind == ConstraintKind::plane ? Vec3{2.0, 3.0, 0.5}
                                                                 : Vec3{5.0 + 2.5, 5.0, 5.0}};
      const std::vector<double> mass = {1.7};
      const std::vector<Vec3> p = {{normal(rng), normal(rng), normal(rng)}};
      const Outcome expected = generic(row, x, p, mass, box, tolerance);
      std::vector<Vec3> lean = p;
      const double lambda = reflect_lone_row(row, x.data(), box, mass, tolerance, lean.data());
      ASSERT_GE(lambda, 0.0);
      EXPECT_NEAR(lambda, expected.impulse, 1e-14 * std::max(1.0, lambda));
      expect_close(lean[0], expected.p[0], std::max(1.0, lambda));
      EXPECT_NEAR(kinetic(lean, mass), kinetic(p, mass), 1e-13 * kinetic(p, mass));
    }
  }
}

TEST(LoneRowReflection, CoincidentParticlesAreLeftToTheGenericPath) {
  const Box box({0, 0, 0}, {5, 5, 5}, {true, true, true});
  const std::vector<Vec3> x = {{1, 1, 1}, {1, 1, 1}};
  std::vector<Vec3> p = {{1, 0, 0}, {-1, 0, 0}};
  Constraint row;
  row.kind = ConstraintKind::sphere_pair;
  row.i = 0, row.j = 1, row.length = 1.0;
  EXPECT_LT(reflect_lone_row(row, x.data(), box, {1.0, 1.0}, 1e-10, p.data()), 0.0);
  EXPECT_EQ(p[0].x, 1.0);
}

}  // namespace
}  // namespace deli
