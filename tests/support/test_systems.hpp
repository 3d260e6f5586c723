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
