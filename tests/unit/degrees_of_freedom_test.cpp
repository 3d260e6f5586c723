// The count of degrees of freedom (README "Temperature"): 3N, less the rank of the rods and
// strings, less the conserved momentum components. Each expectation is the rule applied by hand to
// the geometry of the case.
#include "simulation/degrees_of_freedom.hpp"

#include <gtest/gtest.h>

#include "constraints/equality_rank.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

Particles cloud(std::size_t n) {
  Particles p;
  p.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.mass[i] = 1.0 + 0.1 * static_cast<double>(i % 3);
    p.position[i] = {std::sin(1.0 + i), std::cos(2.0 * i), 0.3 * static_cast<double>(i)};
    p.velocity[i] = {0.1 * i, -0.2, std::cos(3.0 * i)};
  }
  return p;
}

ExternalActions open_box() {
  ExternalActions a;
  a.periodic = {false, false, false};
  return a;
}

TEST(DegreesOfFreedom, PeriodicBoxConservesTheThreeMomentumComponents) {
  const DegreesOfFreedom dof = count_degrees_of_freedom(cloud(10), 4, ExternalActions{});
  EXPECT_EQ(dof.translations, 3);
  EXPECT_EQ(dof.rotations, 0);
  EXPECT_EQ(dof.count(), 30 - 4 - 3);
}

TEST(DegreesOfFreedom, OpenBoxAlsoConservesAngularMomentum) {
  EXPECT_EQ(count_degrees_of_freedom(cloud(10), 0, open_box()).count(), 30 - 6);
}

TEST(DegreesOfFreedom, StraightChainHasTwoRotations) {
  Particles p = cloud(4);
  for (std::size_t i = 0; i < 4; ++i) p.position[i] = {1.0 * i, 0, 0};
  const DegreesOfFreedom dof = count_degrees_of_freedom(p, 3, open_box());
  EXPECT_EQ(dof.rotations, 2);
  EXPECT_EQ(dof.count(), 12 - 3 - 3 - 2);
}

TEST(DegreesOfFreedom, SlitConservesMomentumAlongItsWallsOnly) {
  // Periodic in x and y, walls normal to z: translations x and y; no rotation (two
  // periodic axes).
  ExternalActions slit;
  slit.periodic = {true, true, false};
  slit.directions = {{0, 0, 1}, {0, 0, -1}};
  const DegreesOfFreedom dof = count_degrees_of_freedom(cloud(10), 0, slit);
  EXPECT_EQ(dof.translations, 2);
  EXPECT_EQ(dof.rotations, 0);
}

TEST(DegreesOfFreedom, FloorInOpenBoxLeavesRotationAboutItsNormal) {
  ExternalActions floor = open_box();
  floor.directions = {{0, 0, 1}};
  const DegreesOfFreedom dof = count_degrees_of_freedom(cloud(10), 0, floor);
  EXPECT_EQ(dof.translations, 2);
  EXPECT_EQ(dof.rotations, 1);
}

TEST(DegreesOfFreedom, SphereWallConservesAngularMomentumAboutItsCentre) {
  ExternalActions sphere = open_box();
  sphere.centres = {{1, 2, 3}};
  const DegreesOfFreedom dof = count_degrees_of_freedom(cloud(10), 0, sphere);
  EXPECT_EQ(dof.translations, 0);
  EXPECT_EQ(dof.rotations, 3);
}

TEST(DegreesOfFreedom, PendulaOnALineUnderGravityConserveNothing) {
  // Newton's cradle: strings from points on the x axis, gravity along -y.
  ExternalActions cradle = open_box();
  cradle.centres = {{0, 0, 0}, {0.5, 0, 0}, {1.0, 0, 0}};
  cradle.directions = {{0, -9.8, 0}};
  EXPECT_EQ(count_degrees_of_freedom(cloud(3), 3, cradle).count(), 9 - 3);
  // Without gravity they could turn about the line through their anchors.
  cradle.directions.clear();
  EXPECT_EQ(count_degrees_of_freedom(cloud(3), 3, cradle).rotations, 1);
}

TEST(DegreesOfFreedom, LangevinBathConservesNothing) {
  ExternalActions bath;
  bath.bath_on_each_particle = true;
  EXPECT_EQ(count_degrees_of_freedom(cloud(10), 4, bath).count(), 30 - 4);
}

TEST(DegreesOfFreedom, SetTemperatureRemovesConservedMomentaThenScales) {
  Particles p = cloud(12);
  const DegreesOfFreedom dof = count_degrees_of_freedom(p, 0, open_box());
  set_temperature(p, dof, 1.7);
  Vec3 momentum, angular, com;
  double mass = 0, twice_kinetic = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    com += p.position[i] * p.mass[i];
    mass += p.mass[i];
  }
  com *= 1.0 / mass;
  for (std::size_t i = 0; i < p.size(); ++i) {
    momentum += p.velocity[i] * p.mass[i];
    angular += cross(p.position[i] - com, p.velocity[i] * p.mass[i]);
    twice_kinetic += p.mass[i] * norm2(p.velocity[i]);
  }
  EXPECT_LT(norm(momentum), 1e-13);
  EXPECT_LT(norm(angular), 1e-13);
  EXPECT_NEAR(twice_kinetic / dof.count(), 1.7, 1e-13);
}

// From an input: rods and walls of the default input's kind.
TEST(DegreesOfFreedom, InputWithRodsAndSlitWalls) {
  RunInput input = testing::input_from(
      "[system]\nboundary = \"ppf\"\n[system.chains]\ncount = 5\nlength = 4\ndensity = 0.3\n"
      "bond_length = 1.0\nmin_distance = 0.95\nwall_clearance = 0.5\nseed = 3\n"
      "[forcefield.pair]\nstyle = \"none\"\n[constraints]\nbonds = \"rigid\"\n"
      "walls = [{ type = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }]\n"
      "[integrator]\ntype = \"gvi\"\ntimestep = 0.001\n[run]\nsteps = 0\n");
  EXPECT_EQ(input.degrees_of_freedom.count(), 3 * 20 - 15 - 2);
}

// Rods remove their rank, not their number (expected ranks from rigidity counting: a rigid
// body in 3D has 3n - 6 independent distance constraints, a rigid planar framework 2n - 3,
// since rods in a plane have no out-of-plane gradient).
Constraint rod(std::int32_t i, std::int32_t j, const std::vector<Vec3>& x) {
  return {ConstraintKind::rod, i, j, norm(x[i] - x[j]), {}, {}};
}

const Box kUnboundedBox({-10, -10, -10}, {10, 10, 10}, {false, false, false});

TEST(EqualityRank, ChainOfRodsIsIndependent) {
  const std::vector<Vec3> x = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}};
  const std::vector<Constraint> rows = {rod(0, 1, x), rod(1, 2, x), rod(2, 3, x)};
  EXPECT_EQ(independent_equalities(rows, x.data(), x.size(), kUnboundedBox), 3u);
}

TEST(EqualityRank, FlatSquareWithBothDiagonalsHasRankFive) {
  const std::vector<Vec3> x = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  std::vector<Constraint> rows;
  for (std::int32_t i = 0; i < 4; ++i)
    for (std::int32_t j = i + 1; j < 4; ++j) rows.push_back(rod(i, j, x));
  EXPECT_EQ(independent_equalities(rows, x.data(), x.size(), kUnboundedBox), 5u);  // 2n - 3
}

TEST(EqualityRank, BipyramidWithItsAxisHasOneRedundantRod) {
  // Triangle 0-1-2 in z = 0, apexes 3 and 4 above and below, each joined to the triangle;
  // the axis 3-4 is the tenth rod of a body that 3n - 6 = 9 already hold rigid.
  const std::vector<Vec3> x = {{1, 0, 0},
                               {-0.5, 0.8660254037844386, 0},
                               {-0.5, -0.8660254037844386, 0},
                               {0, 0, 1},
                               {0, 0, -1}};
  std::vector<Constraint> rows = {rod(0, 1, x), rod(1, 2, x), rod(2, 0, x)};
  for (std::int32_t apex : {3, 4})
    for (std::int32_t i = 0; i < 3; ++i) rows.push_back(rod(apex, i, x));
  EXPECT_EQ(independent_equalities(rows, x.data(), x.size(), kUnboundedBox), 9u);
  rows.push_back(rod(3, 4, x));
  EXPECT_EQ(independent_equalities(rows, x.data(), x.size(), kUnboundedBox), 9u);
}

TEST(EqualityRank, AnchorsOnSeparateAtomsAreIndependent) {
  const std::vector<Vec3> x = {{0, 0, -1}, {2, 0, -1}, {3, 0, -1}};
  std::vector<Constraint> rows;
  for (std::int32_t i = 0; i < 3; ++i) {
    rows.push_back({ConstraintKind::anchor, i, -1, 1.0, x[i] + Vec3{0, 0, 1}, {}});
  }
  rows.push_back(rod(1, 2, x));
  EXPECT_EQ(independent_equalities(rows, x.data(), x.size(), kUnboundedBox), 4u);
}

}  // namespace
}  // namespace deli
