#pragma once

#include <cstdint>
#include <vector>

namespace deli {

// The root of a's tree in a union-find forest (parent[r] == r at a root). Each visited
// node is pointed at its grandparent on the way (path halving), so later finds are short.
inline std::int32_t union_find_root(std::vector<std::int32_t>& parent, std::int32_t a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

}  // namespace deli
