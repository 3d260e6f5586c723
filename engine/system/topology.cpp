#include "system/topology.hpp"

#include <algorithm>

namespace deli {

SpecialPairs find_special_pairs(const Topology& topology, std::size_t particle_count) {
  std::vector<std::vector<std::int32_t>> bonded(particle_count);
  for (const Bond& b : topology.bonds) {
    bonded[b.i].push_back(b.j);
    bonded[b.j].push_back(b.i);
  }
  for (auto& list : bonded) std::sort(list.begin(), list.end());

  SpecialPairs special;
  std::vector<int> separation(particle_count, 0);
  std::vector<std::int32_t> reached;
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(particle_count); ++i) {
    // Breadth-first search to depth 3; `separation` is reset through `reached`.
    reached.assign(1, i);
    separation[i] = -1;
    std::size_t begin = 0;
    for (int depth = 1; depth <= 3; ++depth) {
      const std::size_t end = reached.size();
      for (std::size_t r = begin; r < end; ++r) {
        for (std::int32_t k : bonded[reached[r]]) {
          if (separation[k] != 0) continue;
          separation[k] = depth;
          reached.push_back(k);
        }
      }
      begin = end;
    }
    for (std::size_t r = 1; r < reached.size(); ++r) {
      const std::int32_t j = reached[r];
      if (j > i) special.by_separation[separation[j] - 1].push_back({i, j});
    }
    for (std::int32_t k : reached) separation[k] = 0;
  }
  for (auto& pairs : special.by_separation) std::sort(pairs.begin(), pairs.end());
  return special;
}

}  // namespace deli
