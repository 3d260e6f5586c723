// The contact group and its motion relative to its rigid motion (contact_group.hpp), against
// their definitions: the group is the touched rows' particles with their whole rod clusters;
// the relative momenta carry none of the group's linear or angular momentum, keep the rods'
// lengths (zero relative velocity along each rod when the momenta are tangent), and are the
// momenta themselves less m V for a collinear group (no rotation about its own line).
#include "integrators/contact_group.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "support/constraint_rows.hpp"

namespace deli {
namespace {

using testing::pair_row;

TEST(ContactGroup, HoldsTouchedParticlesAndTheirRodClusters) {
  // Rods 0-1-2 and 4-5; particle 3 free; contact 2-3 touched.
  const std::vector<Constraint> rods = {pair_row(ConstraintKind::rod, 0, 1, 1.0),
                                        pair_row(ConstraintKind::rod, 1, 2, 1.0),
                                        pair_row(ConstraintKind::rod, 4, 5, 1.0)};
  const std::vector<char> group =
      contact_group({pair_row(ConstraintKind::sphere_pair, 2, 3, 0.6)}, rods, 7);
  EXPECT_EQ(group, (std::vector<char>{1, 1, 1, 1, 0, 0, 0}));
}

TEST(ContactGroup, RelativeMomentaCarryNoMomentumAndKeepRods) {
  Particles particles;
  particles.resize(5);
  std::vector<Vec3> p(5);
  for (std::size_t i = 0; i < 5; ++i) {
    particles.mass[i] = 1.0 + 0.3 * static_cast<double>(i);
    particles.position[i] = {std::sin(1.0 + i), std::cos(2.0 * i), 0.7 * static_cast<double>(i)};
    p[i] = {0.4 * std::cos(1.3 * i), -0.2 + 0.1 * i, std::sin(3.0 * i)};
  }
  // A rod 0-1 with its relative velocity along it removed (momenta tangent to the rod).
  const Vec3 e = particles.position[1] - particles.position[0];
  const Vec3 u = e * (1.0 / norm(e));
  const double reduced = 1.0 / (1.0 / particles.mass[0] + 1.0 / particles.mass[1]);
  const double closing =
      dot(p[1] * (1.0 / particles.mass[1]) - p[0] * (1.0 / particles.mass[0]), u);
  p[0] += u * (closing * reduced);
  p[1] -= u * (closing * reduced);
  const std::vector<char> group = {1, 1, 1, 1, 0};
  const Box open({-9, -9, -9}, {9, 9, 9}, {false, false, false});
  const std::vector<Vec3> d = internal_momenta(particles, open, p, group);
  Vec3 momentum, angular;
  for (std::size_t i = 0; i < 5; ++i) {
    momentum += d[i];
    angular += cross(particles.position[i], d[i]);
  }
  EXPECT_LT(norm(momentum), 1e-14);
  EXPECT_LT(norm(angular), 1e-14);
  EXPECT_EQ(norm(d[4]), 0.0);
  const double along_rod =
      dot(d[1] * (1.0 / particles.mass[1]) - d[0] * (1.0 / particles.mass[0]), u);
  EXPECT_LT(std::abs(along_rod), 1e-14);
  // Periodic: the translation alone taken out.
  const Box periodic({-9, -9, -9}, {9, 9, 9}, {true, true, true});
  const std::vector<Vec3> t = internal_momenta(particles, periodic, p, group);
  Vec3 total;
  double mass = 0;
  for (std::size_t i = 0; i < 4; ++i) total += p[i], mass += particles.mass[i];
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_LT(norm(t[i] - (p[i] - total * (particles.mass[i] / mass))), 1e-15);
  }
}

TEST(ContactGroup, CollinearPairKeepsItsRelativeMotionAlongTheLine) {
  // Two beads on the x axis closing head on (the line of a head-on contact): the inertia about
  // the line is zero; nothing is taken out but the translation.
  Particles particles;
  particles.resize(2);
  particles.mass = {1.0, 2.0};
  particles.position = {{-0.3, 0, 0}, {0.3, 0, 0}};
  const std::vector<Vec3> p = {{1.0, 0, 0}, {-0.5, 0, 0}};
  const Box open({-9, -9, -9}, {9, 9, 9}, {false, false, false});
  const std::vector<Vec3> d = internal_momenta(particles, open, p, {1, 1});
  // V = 0.5 / 3 along x: d_i = p_i - m_i V.
  EXPECT_NEAR(d[0].x, 1.0 - 0.5 / 3, 1e-15);
  EXPECT_NEAR(d[1].x, -0.5 - 1.0 / 3, 1e-15);
  EXPECT_EQ(d[0].y, 0.0);
  EXPECT_EQ(d[1].z, 0.0);
}

}  // namespace
}  // namespace deli
