#pragma once

#include <optional>
#include <string>
#include <vector>

#include "system/particles.hpp"

namespace deli {

// The first atom (in index order) whose position, velocity or force (when given) is NaN or
// infinite, described as "atom ID: position (x, y, z)"; nothing when every value is finite.
// A run that blew up (a timestep too large, overlapping atoms) is stopped with this.
std::optional<std::string> first_non_finite_atom(const Particles& particles,
                                                 const std::vector<Vec3>* forces = nullptr);

}  // namespace deli
