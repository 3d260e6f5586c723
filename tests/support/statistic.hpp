#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace deli::testing {

// A named statistic of the integrator; a name it does not report fails the test (a loop
// over the names would pass without checking anything).
inline double statistic(const std::vector<std::pair<std::string, double>>& stats,
                        const std::string& name) {
  for (const auto& [n, value] : stats) {
    if (n == name) return value;
  }
  ADD_FAILURE() << "the integrator reports no statistic '" << name << "'";
  return std::nan("");
}

}  // namespace deli::testing
