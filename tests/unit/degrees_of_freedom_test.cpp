// The count of degrees of freedom (README "Temperature"): 3N, less one per rod or string,
// less the conserved momentum components. Each expectation is the rule applied by hand to
// the geometry of the case.
#include "simulation/degrees_of_freedom.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace deli
