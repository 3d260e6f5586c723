#pragma once

#include <random>
#include <string>

#include "forces/special_bonds.hpp"
#include "input/run_input.hpp"
#include "neighbor/neighbor_list.hpp"

namespace deli::testing {

// A complete input from TOML text (paths relative to the source tree's tests/).
inline RunInput input_from(const std::string& toml) {
  return parse_run_input(toml, std::string(DELI_SOURCE_DIR) + "/tests/inline.toml");
}

// 40 random-walk chains of 30 beads (1200 particles, density 0.5, temperature 1), every bond
// a rod of length 1 (1160 rows in 40 clusters: past the rows from which cluster loops are
// cut into chunks), GVI at h 0.005, with the force field's tables `force_field`.
inline RunInput thirty_bead_rod_chains(const std::string& force_field) {
  return input_from(R"(
[system]
[system.chains]
count = 40
length = 30
density = 0.5
bond_length = 1.0
min_distance = 0.8
seed = 31
[velocities]
temperature = 1.0
seed = 7
)" + force_field + R"(
[constraints]
bonds = "rigid"
rod_length = 1.0
[integrator]
type = "gvi"
timestep = 0.005
[run]
steps = 0
)");
}

// thirty_bead_rod_chains with shifted LJ (cutoff 2.5) between beads not bonded to each other.
inline RunInput thirty_bead_lj_rod_chains() {
  return thirty_bead_rod_chains(R"(
[forcefield.special_bonds]
lj = [0.0, 1.0, 1.0]
[forcefield.pair]
style = "lj/cut"
cutoff = 2.5
shift = true
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]
)");
}

// `count` chains of `length` beads (density 0.6) with harmonic bonds, angles and dihedrals
// and LJ (cutoff 2.5) between beads (the cross-check input
// tests/crosscheck/inputs/chains_dihedrals.toml's force field), and the TOML `more`.
inline RunInput dihedral_chains(int count, int length, const std::string& more = "") {
  return input_from(R"(
[system]
[system.chains]
count = )" + std::to_string(count) +
                    "\nlength = " + std::to_string(length) + R"(
density = 0.6
bond_length = 0.97
min_distance = 0.85
angles = true
dihedrals = true
seed = 21
[forcefield.pair]
style = "lj/cut"
cutoff = 2.5
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]
[forcefield.bond]
style = "harmonic"
coeffs = [{ type = 1, k = 100.0, r0 = 0.97 }]
[forcefield.angle]
style = "harmonic"
coeffs = [{ type = 1, k = 5.0, theta0 = 110.0 }]
[forcefield.dihedral]
style = "harmonic"
coeffs = [{ type = 1, k = 3.0, d = -1, n = 3 }]
[integrator]
timestep = 0.005
[run]
steps = 0
)" + more);
}

// A hard-sphere fluid as inputs/hard_spheres/hs_4000.toml (fcc at packing fraction 0.30)
// with 4 cells^3 spheres (fcc: 4 a cell), at a step of 0.02 (free flight is exact at any
// step), and the TOML `more`.
inline RunInput hard_sphere_fluid(int cells, const std::string& more = "") {
  const std::string n = std::to_string(cells);
  return input_from(R"(
[system]
[system.lattice]
type = "fcc"
density = 0.5729577951308232
cells = [)" + n + ", " +
                    n + ", " + n + R"(]
[velocities]
temperature = 1.0
seed = 30
[forcefield.pair]
style = "none"
[constraints]
hard_spheres = { diameter = 1.0 }
[neighbor]
skin = 0.4
[integrator]
type = "gvi"
timestep = 0.02
[run]
steps = 0
)" + more);
}

// Energies and forces of `input` at its current positions through a fresh neighbour list.
struct Evaluated {
  ForceEvaluation evaluation;
  std::vector<Vec3> force;
};
inline Evaluated evaluate(const RunInput& input, double skin = 0.5, bool tally = true) {
  NeighborList list(input.force_field->neighbor_cutoff(), skin);
  list.set_exclusions({});
  Evaluated out;
  // Exclusions come from the topology exactly as the run does it.
  const SpecialPairs special =
      find_special_pairs(input.system.topology, input.system.particles.size());
  std::vector<std::array<std::int32_t, 2>> excluded;
  for (const ExcludedSpecialPair& p :
       excluded_special_pairs(special, input.force_field->special_lj)) {
    excluded.push_back({p.i, p.j});
  }
  list.set_exclusions(excluded);
  list.build(input.system.particles.position, input.system.box);
  out.evaluation = input.force_field->compute(input.system, list, out.force, tally);
  return out;
}

// Moves every particle by a uniform random displacement of at most `amplitude` per axis.
inline void jiggle(Particles& p, double amplitude, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  for (Vec3& x : p.position) x += Vec3{u(rng), u(rng), u(rng)};
}

}  // namespace deli::testing
