#pragma once

#include <optional>
#include <string>
#include <vector>

#include "system/box.hpp"
#include "system/particles.hpp"

namespace deli {

// The first atom (in index order) whose position, velocity or force (when given) is NaN or
// infinite, described as "atom ID: position (x, y, z)"; nothing when every value is finite.
// A run that blew up (a timestep too large, overlapping atoms) is stopped with this.
std::optional<std::string> first_non_finite_atom(const Particles& particles,
                                                 const std::vector<Vec3>* forces = nullptr);

// The first atom that ran away: a coordinate more than 1e15 from the box (where a double no
// longer resolves an atom's size), or more than 1e9 periods out along a periodic axis (its
// image count would overflow). No run that means anything gets there; a blown-up one does.
std::optional<std::string> first_runaway_atom(const Particles& particles, const Box& box);

// Whether atoms [begin, end) hold neither a non-finite position or velocity nor a runaway
// position: where this is true, the two scans above name none of them. Without a branch per
// atom, for a pass that checks a range on the way (ForceEngine::ensure_neighbors' wrap); the
// scans above then name the atom, in their order, only where some range failed.
bool atoms_usable(const Particles& particles, const Box& box, std::size_t begin, std::size_t end);

}  // namespace deli
