#pragma once

#include <vector>

#include "core/vec3.hpp"

namespace deli::testing {

// Whether two lists of vectors are the same numbers bit for bit (a result expected to repeat
// exactly, not to round-off).
inline bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z) return false;
  }
  return true;
}

}  // namespace deli::testing
