#pragma once

#include <cstdint>

#include "system/system.hpp"

namespace deli {

// Face-centred cubic lattice filling a periodic box of cells unit cells at the given number
// density. Sites take the types 0, 1, ... in turn, with masses[type].
struct FccLattice {
  double density = 0.8442;
  std::array<int, 3> cells{10, 10, 10};
  std::vector<double> masses{1.0};  // one per type
};
System build_fcc(const FccLattice& lattice);

// `count` linear chains of `length` beads (type 0, bonds of type 0, angles of type 0 when
// `angles`, dihedrals of type 0 when `dihedrals`) grown as random walks with fixed bond length in a
// periodic cubic box at the given bead number density, with no two beads closer than min_distance
// (minimum image).
struct RandomChains {
  int count = 100;
  int length = 20;
  double density = 0.85;
  double bond_length = 0.97;
  double min_distance = 0.9;
  double mass = 1.0;
  bool angles = false;
  bool dihedrals = false;
  std::uint64_t seed = 1;
  int attempts_per_bead = 100;
  // Along open axes beads stay within [lo + clearance, hi - clearance] (between walls).
  std::array<bool, 3> periodic{true, true, true};
  double wall_clearance = 0.0;
};
// Throws InputError when the walk cannot be grown (too dense, min_distance too large).
System build_random_chains(const RandomChains& chains);

// Maxwell-Boltzmann velocities at `temperature` (k_B = 1) from `seed`, with the
// total momentum removed and then rescaled to exactly that temperature with 3N - 3
// degrees of freedom (LAMMPS' `velocity create` convention).
void assign_maxwell_boltzmann(Particles& particles, double temperature, std::uint64_t seed);

}  // namespace deli
