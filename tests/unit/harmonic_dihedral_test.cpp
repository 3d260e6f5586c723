// LAMMPS' dihedral_style harmonic, E = K [1 + d cos(n phi)], at torsion angles set by
// construction: the energy is the formula's (analytic), the forces sum to zero and the
// torque on l about the j-k axis is -dE/dphi.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "bonded/bonded_style.hpp"
#include "neighbor/neighbor_list.hpp"
#include "system/system.hpp"

namespace deli {
namespace {

// Atoms i-j-k-l with the j-k bond along z and torsion angle phi: i in the xz plane, l
// turned by phi about z (phi = 0 cis, 180 trans, IUPAC), in a box far larger than them.
System four_atoms(double phi) {
  System system;
  system.box = Box({-10, -10, -10}, {10, 10, 10}, {true, true, true});
  system.atom_types = {AtomType{1.0, 0.5}};
  Particles& p = system.particles;
  p.resize(4);
  p.position = {{1.3, 0.0, -0.2},
                {0.0, 0.0, 0.0},
                {0.0, 0.0, 1.1},
                {0.9 * std::cos(phi), 0.9 * std::sin(phi), 1.4}};
  for (std::size_t a = 0; a < 4; ++a) p.id[a] = static_cast<std::int64_t>(a + 1);
  system.topology.dihedrals = {{0, 1, 2, 3, 0}};
  system.topology.dihedral_types = 1;
  return system;
}

struct Torsion {
  double energy;
  std::vector<Vec3> force;
};
Torsion evaluate(double k, double d, double n, double phi) {
  const BondedStyle* style = find_bonded_style(BondedKind::dihedral, "harmonic");
  const auto term = style->make_term({{k, d, n}}, {});
  const System system = four_atoms(phi);
  NeighborList none(0.0, 0.0);
  Torsion out{0.0, std::vector<Vec3>(4)};
  SymTensor virial;
  out.energy = term->compute(system, none, out.force, virial, true);
  return out;
}

TEST(HarmonicDihedral, EnergyIsTheFormulaAtKnownAngles) {
  const double degree = std::numbers::pi / 180.0;
  for (const double phi_degrees : {0.0, 30.0, 60.0, 90.0, 135.0, 180.0, 250.0, 315.0}) {
    for (const auto& [d, n] :
         {std::pair{1.0, 1.0}, {-1.0, 1.0}, {1.0, 2.0}, {-1.0, 3.0}, {1.0, 0.0}, {-1.0, 0.0}}) {
      const double k = 1.7, phi = phi_degrees * degree;
      const Torsion t = evaluate(k, d, n, phi);
      const double expected = k * (1.0 + d * std::cos(n * phi));
      EXPECT_NEAR(t.energy, expected, 1e-14) << "phi " << phi_degrees << " d " << d << " n " << n;
      Vec3 sum;
      for (const Vec3& f : t.force) sum += f;
      EXPECT_LT(norm(sum), 1e-13) << "phi " << phi_degrees;
      // Turning l alone about z (the j-k axis) by a turns the construction's angle by a;
      // E is even in phi, so the torque on l is -dE/dphi = K d n sin(n phi) whichever sign
      // the torsion convention gives phi.
      const Vec3 x = four_atoms(phi).particles.position[3];
      const double torque = x.x * t.force[3].y - x.y * t.force[3].x;
      EXPECT_NEAR(torque, k * d * n * std::sin(n * phi), 1e-13)
          << "phi " << phi_degrees << " d " << d << " n " << n;
    }
  }
}

// Trans (180 degrees) is the minimum for d = +1, n = 1 (and the maximum for d = -1): the
// IUPAC convention that LAMMPS and OpenMM share.
TEST(HarmonicDihedral, TransIsTheMinimumForPositiveD) {
  const double pi = std::numbers::pi;
  EXPECT_NEAR(evaluate(2.0, 1.0, 1.0, pi).energy, 0.0, 1e-15);
  EXPECT_NEAR(evaluate(2.0, 1.0, 1.0, 0.0).energy, 4.0, 1e-15);
  EXPECT_NEAR(evaluate(2.0, -1.0, 1.0, pi).energy, 4.0, 1e-15);
}

}  // namespace
}  // namespace deli
