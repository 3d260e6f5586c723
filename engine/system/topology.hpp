#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace deli {

// Bonded connectivity by internal particle index; types are 0-based.
struct Bond {
  std::int32_t i, j;
  int type;
};
struct Angle {
  std::int32_t i, j, k;  // j is the vertex
  int type;
};
struct Dihedral {
  std::int32_t i, j, k, l;  // the torsion about the j-k bond
  int type;
};

struct Topology {
  std::vector<Bond> bonds;
  std::vector<Angle> angles;
  std::vector<Dihedral> dihedrals;
  int bond_types = 0;
  int angle_types = 0;
  int dihedral_types = 0;
};

// Pairs separated by 1, 2 or 3 bonds (1-2, 1-3, 1-4 neighbours), each pair once with
// i < j, by their smallest separation. What LAMMPS' special_bonds acts on.
struct SpecialPairs {
  std::array<std::vector<std::array<std::int32_t, 2>>, 3> by_separation;
};
SpecialPairs find_special_pairs(const Topology& topology, std::size_t particle_count);

}  // namespace deli
