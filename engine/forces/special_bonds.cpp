#include "forces/special_bonds.hpp"

namespace deli {

std::vector<ExcludedSpecialPair> excluded_special_pairs(const SpecialPairs& special,
                                                        const std::array<double, 3>& factors) {
  std::vector<ExcludedSpecialPair> excluded;
  for (int s = 0; s < 3; ++s) {
    if (factors[s] == 1.0) continue;
    for (const auto& [i, j] : special.by_separation[s])
      excluded.push_back({i, j, s + 1, factors[s]});
  }
  return excluded;
}

}  // namespace deli
