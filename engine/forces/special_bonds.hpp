#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "system/topology.hpp"

namespace deli {

// A 1-2, 1-3 or 1-4 neighbour pair (i < j) that LAMMPS' special_bonds lj takes out of the
// neighbour list, with its factor: 0 leaves it out, a factor strictly between 0 and 1 has it
// computed on its own, scaled.
struct ExcludedSpecialPair {
  std::int32_t i, j;
  int separation;  // 1, 2 or 3 bonds
  double factor;   // in [0, 1)
  bool scaled() const { return factor != 0.0; }
};

// The special_bonds rule, the one place it is written: a pair whose factor (`factors`, for
// 1-2, 1-3 and 1-4 neighbours) is 1 stays an ordinary pair; every other one is excluded.
// In order of separation, then in `special`'s order.
std::vector<ExcludedSpecialPair> excluded_special_pairs(const SpecialPairs& special,
                                                        const std::array<double, 3>& factors);

}  // namespace deli
