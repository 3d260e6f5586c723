#pragma once

#include <cstddef>
#include <vector>

#include "constraints/constraint.hpp"
#include "core/vec3.hpp"
#include "system/box.hpp"

namespace deli {

// How many of the equality rows (rods, anchors) are independent at positions x: the rank
// of their Jacobian, which is what they remove from the momenta's degrees of freedom. A
// rigid loop braced with a redundant rod (a bipyramid with its axis) has one row more
// than its rank; a tree of rods (every chain) has none, and is counted without a
// factorisation.
std::size_t independent_equalities(const std::vector<Constraint>& rows, const Vec3* x,
                                   std::size_t particle_count, const Box& box);

}  // namespace deli
