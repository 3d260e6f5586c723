#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace deli::testing {

// The mean of a correlated series and its standard error from block averages: the series
// cut into `blocks` consecutive blocks (each much longer than the correlation time), the
// error of the mean being the spread of the block means / sqrt(blocks).
struct Estimate {
  double value = 0, error = 0;
};
inline Estimate block_estimate(const std::vector<double>& series, int blocks = 20) {
  const std::size_t per = series.size() / static_cast<std::size_t>(blocks);
  std::vector<double> means(static_cast<std::size_t>(blocks), 0.0);
  for (std::size_t b = 0; b < means.size(); ++b) {
    for (std::size_t k = 0; k < per; ++k) means[b] += series[b * per + k];
    means[b] /= static_cast<double>(per);
  }
  double mean = 0, spread = 0;
  for (double m : means) mean += m;
  mean /= blocks;
  for (double m : means) spread += (m - mean) * (m - mean);
  return {mean, std::sqrt(spread / (blocks - 1) / blocks)};
}

// The variance of the series about its mean (not of the mean).
inline double variance(const std::vector<double>& series) {
  double sum = 0, sum2 = 0;
  for (double x : series) sum += x, sum2 += x * x;
  const double n = static_cast<double>(series.size());
  return (sum2 - sum * sum / n) / (n - 1);
}

}  // namespace deli::testing
