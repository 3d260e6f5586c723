// Particles put in spatial order (system/particle_order.hpp, ConstraintSet::renumber,
// reorder_run_input), as LAMMPS' atom_modify sort: a relabelling, so every quantity of a
// particle follows it. Expected values: the spatial order by construction (bins along a
// line), the system before the reordering (bit for bit where nothing is computed), and the
// forces and energies of the same configuration in the input's order (a relabelling changes
// only the order of the sums: to rounding).
#include "system/particle_order.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <utility>

#include "support/test_systems.hpp"

namespace deli {
namespace {

// Bit for bit (Vec3 has no ==: positions are compared within a tolerance everywhere else).
bool same_bits(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}
bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(),
                    [](const Vec3& x, const Vec3& y) { return same_bits(x, y); });
}

ParticleOrder shuffled_order(std::size_t n, unsigned seed) {
  ParticleOrder order(n);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 random(seed);
  std::shuffle(order.begin(), order.end(), random);
  return order;
}

// Five atoms bonded in a chain with two angles and a dihedral, numbered against the chain.
System five_atom_chain() {
  System s;
  s.box = Box({0, 0, 0}, {10, 10, 10}, {true, true, true});
  s.particles.resize(5);
  for (std::size_t i = 0; i < 5; ++i) {
    s.particles.position[i] = {9.0 - 2.0 * static_cast<double>(i), 1.0 + 0.1 * i, 2.0};
    s.particles.velocity[i] = {0.1 * i, -0.2, 0.3};
    s.particles.id[i] = static_cast<std::int64_t>(100 + i);
    s.particles.mass[i] = 1.0 + static_cast<double>(i);
    s.particles.type[i] = static_cast<int>(i % 2);
    s.particles.molecule[i] = 7;
    s.particles.image[i] = {static_cast<int>(i), 0, -1};
  }
  s.topology.bonds = {{0, 1, 0}, {1, 2, 0}, {2, 3, 0}, {3, 4, 0}};
  s.topology.angles = {{0, 1, 2, 0}, {2, 3, 4, 0}};
  s.topology.dihedrals = {{0, 1, 2, 3, 0}};
  return s;
}

TEST(ParticleOrder, SpatialOrderListsTheBinsAlongTheAxesXFirst) {
  // Lone particles on a line along x (y 1.0-1.4, one bin), listed from its far end: the
  // order reverses them, but for two in one bin, which keep the order they had.
  System s = five_atom_chain();
  s.topology = Topology{};
  s.particles.position[3] = {1.2, 1.3, 2.0};
  s.particles.position[4] = {1.1, 1.4, 2.0};
  EXPECT_EQ(spatial_order(s, 1.0), (ParticleOrder{3, 4, 2, 1, 0})) << "x bins 9, 7, 5, 1, 1";
  // Bins along y outrank x: a particle one bin up in y comes after every one below it.
  s.particles.position[4].y = 5.5;
  EXPECT_EQ(spatial_order(s, 1.0), (ParticleOrder{3, 2, 1, 0, 4}));
  // and z outranks y.
  s.particles.position[1].z = 7.0;
  EXPECT_EQ(spatial_order(s, 1.0), (ParticleOrder{3, 2, 0, 4, 1}));
  EXPECT_TRUE(is_identity(spatial_order(s, 100.0)));
  // Bonded particles stay together, in their order, in the bin of the first of them.
  s.topology.bonds = {{4, 1, 0}};
  EXPECT_EQ(spatial_order(s, 1.0), (ParticleOrder{3, 2, 0, 1, 4}));
  s.topology.bonds = {{4, 1, 0}, {1, 3, 0}};
  EXPECT_EQ(spatial_order(s, 1.0), (ParticleOrder{2, 0, 1, 3, 4})) << "in the bin of 1";
  EXPECT_TRUE(is_identity(spatial_order(five_atom_chain(), 1.0))) << "one chain";
}

TEST(ParticleOrder, ReorderMovesEveryArrayAndRenamesTheTopologyAndBackIsTheSameBits) {
  const System before = five_atom_chain();
  System s = before;
  const ParticleOrder order{3, 0, 4, 2, 1};
  reorder(s, order);
  const Particles& p = s.particles;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto i = static_cast<std::size_t>(order[k]);
    EXPECT_EQ(p.id[k], before.particles.id[i]);
    EXPECT_TRUE(same_bits(p.position[k], before.particles.position[i]));
    EXPECT_TRUE(same_bits(p.velocity[k], before.particles.velocity[i]));
    EXPECT_EQ(p.mass[k], before.particles.mass[i]);
    EXPECT_EQ(p.type[k], before.particles.type[i]);
    EXPECT_EQ(p.image[k], before.particles.image[i]);
    EXPECT_EQ(p.origin[k], order[k]);
  }
  // Every bonded term joins the same atoms (by id), in the same order of terms.
  auto ids = [](const System& sys, std::initializer_list<std::int32_t> at) {
    std::vector<std::int64_t> out;
    for (const std::int32_t i : at) out.push_back(sys.particles.id[static_cast<std::size_t>(i)]);
    return out;
  };
  for (std::size_t b = 0; b < before.topology.bonds.size(); ++b) {
    const Bond &x = before.topology.bonds[b], &y = s.topology.bonds[b];
    EXPECT_EQ(ids(before, {x.i, x.j}), ids(s, {y.i, y.j}));
  }
  for (std::size_t a = 0; a < before.topology.angles.size(); ++a) {
    const Angle &x = before.topology.angles[a], &y = s.topology.angles[a];
    EXPECT_EQ(ids(before, {x.i, x.j, x.k}), ids(s, {y.i, y.j, y.k}));
  }
  const Dihedral &x = before.topology.dihedrals[0], &y = s.topology.dihedrals[0];
  EXPECT_EQ(ids(before, {x.i, x.j, x.k, x.l}), ids(s, {y.i, y.j, y.k, y.l}));
  // Reordered twice, then listed in the input's order: the system as it was.
  reorder(s, ParticleOrder{1, 2, 0, 4, 3});
  const System back = in_input_order(s);
  EXPECT_TRUE(back.particles.origin.empty());
  EXPECT_EQ(back.particles.id, before.particles.id);
  EXPECT_TRUE(same_bits(back.particles.position, before.particles.position));
  EXPECT_TRUE(same_bits(back.particles.velocity, before.particles.velocity));
  EXPECT_EQ(back.particles.image, before.particles.image);
  for (std::size_t b = 0; b < before.topology.bonds.size(); ++b) {
    EXPECT_EQ(back.topology.bonds[b].i, before.topology.bonds[b].i);
    EXPECT_EQ(back.topology.bonds[b].j, before.topology.bonds[b].j);
  }
  EXPECT_EQ(back.topology.dihedrals[0].l, before.topology.dihedrals[0].l);
  EXPECT_TRUE(
      same_bits(in_input_order(s.particles.position, s.particles), before.particles.position));
  // A checkpoint's ids in this order give it back; ids of other atoms give nothing.
  EXPECT_EQ(order_of_ids(s.particles.id, before.particles), s.particles.origin);
  EXPECT_FALSE(order_of_ids(before.particles.id, before.particles));
  std::vector<std::int64_t> other = s.particles.id;
  other[0] = 999;
  EXPECT_FALSE(order_of_ids(other, before.particles));
}

TEST(ParticleOrder, RenumberedConstraintsJoinTheSameAtoms) {
  RunInput input = testing::thirty_bead_lj_rod_chains();
  input.constraints.hard_spheres = true;
  input.constraints.always_checked_pairs = {{0, 2}, {5, 7}, {40, 42}};
  const RunInput before = testing::thirty_bead_lj_rod_chains();
  const ParticleOrder order = shuffled_order(input.system.particles.size(), 3);
  reorder_run_input(input, order);
  const Particles &p = input.system.particles, &q = before.system.particles;
  auto id_pair = [](const Particles& particles, std::int32_t a, std::int32_t b) {
    return std::minmax(particles.id[static_cast<std::size_t>(a)],
                       particles.id[static_cast<std::size_t>(b)]);
  };
  ASSERT_EQ(input.constraints.equalities.size(), before.constraints.equalities.size());
  for (std::size_t k = 0; k < input.constraints.equalities.size(); ++k) {
    const Constraint &c = input.constraints.equalities[k], &d = before.constraints.equalities[k];
    EXPECT_LT(c.i, c.j) << "a rod joins i < j";
    EXPECT_EQ(id_pair(p, c.i, c.j), id_pair(q, d.i, d.j));
    EXPECT_EQ(c.length, d.length);
  }
  std::set<std::pair<std::int64_t, std::int64_t>> renumbered, expected;
  for (const auto& [a, b] : input.constraints.unconstrained_pairs) {
    EXPECT_LT(a, b);
    renumbered.insert(id_pair(p, a, b));
  }
  for (const auto& [a, b] : before.constraints.unconstrained_pairs)
    expected.insert(id_pair(q, a, b));
  EXPECT_EQ(renumbered, expected);
  EXPECT_TRUE(std::is_sorted(input.constraints.unconstrained_pairs.begin(),
                             input.constraints.unconstrained_pairs.end()))
      << "searched by binary search";
  std::set<std::pair<std::int64_t, std::int64_t>> checked;
  for (const auto& [a, b] : input.constraints.always_checked_pairs)
    checked.insert(id_pair(p, a, b));
  EXPECT_EQ(checked, (std::set<std::pair<std::int64_t, std::int64_t>>{
                         id_pair(q, 0, 2), id_pair(q, 5, 7), id_pair(q, 40, 42)}));
}

// The force field made anew for the reordered system (its bonds, angles, dihedrals and
// special pairs from the renamed topology) gives every atom the force it had, to rounding,
// and the same energies, term by term.
TEST(ParticleOrder, ForcesAndEnergiesFollowTheAtoms) {
  const std::string special = "[forcefield.special_bonds]\nlj = [0.0, 0.0, 0.5]\n";
  const RunInput before = testing::dihedral_chains(20, 12, special);
  RunInput input = testing::dihedral_chains(20, 12, special);
  reorder_run_input(input, shuffled_order(input.system.particles.size(), 11));
  const testing::Evaluated a = testing::evaluate(before), b = testing::evaluate(input);
  double largest = 0;
  for (const Vec3& f : a.force) largest = std::max(largest, norm(f));
  std::map<std::int64_t, Vec3> by_id;
  for (std::size_t i = 0; i < a.force.size(); ++i)
    by_id[before.system.particles.id[i]] = a.force[i];
  for (std::size_t k = 0; k < b.force.size(); ++k) {
    const Vec3 expected = by_id.at(input.system.particles.id[k]);
    EXPECT_LE(norm(b.force[k] - expected), 1e-12 * largest)
        << "atom " << input.system.particles.id[k];
  }
  const double scale = std::abs(a.evaluation.potential);
  EXPECT_NEAR(b.evaluation.potential, a.evaluation.potential, 1e-12 * scale);
  ASSERT_EQ(a.evaluation.names, b.evaluation.names);
  ASSERT_EQ(a.evaluation.energies.size(), 4u) << "pair, bond, angle, dihedral";
  for (std::size_t t = 0; t < a.evaluation.energies.size(); ++t) {
    EXPECT_NEAR(b.evaluation.energies[t], a.evaluation.energies[t], 1e-12 * scale)
        << a.evaluation.names[t];
    EXPECT_NE(a.evaluation.energies[t], 0.0) << a.evaluation.names[t];
  }
  auto trace = [](const SymTensor& t) { return t.xx + t.yy + t.zz; };
  EXPECT_NEAR(trace(b.evaluation.virial), trace(a.evaluation.virial),
              1e-12 * std::abs(trace(a.evaluation.virial)));
}

}  // namespace
}  // namespace deli
