#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace deli::testing {

// Bounded or drifting: the least-squares line through an energy error series (samples
// equally spaced) gives the trend over the whole run, |slope| * span; what the line leaves
// is the fluctuation, measured as the largest |residual|. A bounded error oscillates about
// a level line (trend well below the fluctuation); a drift of any size makes the trend
// grow with the run while the fluctuation does not. Comparing the largest error of the two
// halves cannot tell them apart: a pure linear drift gives exactly 2, a bounded error
// that peaks late gives the same.
struct EnergyTrend {
  double trend = 0;         // |fitted change| from the first sample to the last
  double signed_trend = 0;  // the fitted change with its sign
  double fluctuation = 0;   // max |residual| about the fitted line
  // The trend as a fraction of the fluctuation: below 1 the run is dominated by bounded
  // oscillation; a drifting run gives tens and more.
  double ratio() const { return trend / std::max(fluctuation, 1e-300); }
};

inline EnergyTrend energy_trend(const std::vector<double>& error) {
  const std::size_t n = error.size();
  EnergyTrend r;
  if (n < 3) return r;
  double mean_k = 0, mean_e = 0;
  for (std::size_t k = 0; k < n; ++k) mean_k += static_cast<double>(k), mean_e += error[k];
  mean_k /= static_cast<double>(n);
  mean_e /= static_cast<double>(n);
  double skk = 0, ske = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double dk = static_cast<double>(k) - mean_k;
    skk += dk * dk;
    ske += dk * (error[k] - mean_e);
  }
  const double slope = ske / skk;
  r.signed_trend = slope * static_cast<double>(n - 1);
  r.trend = std::abs(r.signed_trend);
  for (std::size_t k = 0; k < n; ++k) {
    const double fitted = mean_e + slope * (static_cast<double>(k) - mean_k);
    r.fluctuation = std::max(r.fluctuation, std::abs(error[k] - fitted));
  }
  return r;
}

}  // namespace deli::testing
