#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "system/system.hpp"

namespace deli {

// An order of the particles: order[k] is the index of the particle put k-th.
using ParticleOrder = std::vector<std::int32_t>;

// The particles in spatial bins of side at least `bin` (x fastest, then y, then z), as
// LAMMPS' atom_modify sort: particles near each other in space come near each other in
// memory, so that a pass over the particles reads their neighbours' lines from cache, and a
// chunk of them is a region of space. The particles joined by bonds stay together, in their
// present order, in the bin of the first of them: a chain's rods and bonds read consecutive
// particles (binned bead by bead, the default input's chains ran 6 % slower than in their
// data file's chain order, bench/README.md). A bin's molecules and lone particles come in
// their present order.
ParticleOrder spatial_order(const System& system, double bin);
bool is_identity(const ParticleOrder& order);
// The new index of each particle: inverse(order)[order[k]] = k.
ParticleOrder inverse(const ParticleOrder& order);

template <class T>
std::vector<T> permuted(const std::vector<T>& values, const ParticleOrder& order) {
  std::vector<T> out;
  out.reserve(order.size());
  for (const std::int32_t i : order) out.push_back(values[static_cast<std::size_t>(i)]);
  return out;
}

// The order that lists the particles by `ids` (a checkpoint's), when that is another
// arrangement of their own ids; nothing when it is theirs or not an arrangement of them.
std::optional<ParticleOrder> order_of_ids(const std::vector<std::int64_t>& ids,
                                          const Particles& particles);

// Puts particle order[k] at index k: every per-particle array (and `origin`), and the
// topology's indices (its terms keep their order).
void reorder(System& system, const ParticleOrder& order);

// Per-particle values (index order) listed in the order of the input: as they are while
// the particles are in that order, and scattered back by `origin` once they are not.
template <class T>
const std::vector<T>& in_input_order(const std::vector<T>& values, const Particles& particles,
                                     std::vector<T>& scratch) {
  if (particles.origin.empty()) return values;
  scratch.resize(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    scratch[static_cast<std::size_t>(particles.origin[i])] = values[i];
  }
  return scratch;
}
template <class T>
std::vector<T> in_input_order(const std::vector<T>& values, const Particles& particles) {
  std::vector<T> scratch;
  if (particles.origin.empty()) return values;
  in_input_order(values, particles, scratch);
  return scratch;
}
// The system with its particles in the input's order (a final data file).
System in_input_order(const System& system);

}  // namespace deli
