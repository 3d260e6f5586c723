#include "pair/pair_coefficients.hpp"

#include <cmath>

namespace deli {

PairCoefficients::PairCoefficients(int type_count, double global_cutoff)
    : type_count_(type_count),
      global_cutoff_(global_cutoff),
      table_(static_cast<std::size_t>(type_count * type_count)),
      given_(static_cast<std::size_t>(type_count * type_count), false) {}

void PairCoefficients::set(int a, int b, std::vector<double> values, std::optional<double> cutoff) {
  const PairCoefficient c{std::move(values), cutoff.value_or(global_cutoff_)};
  table_[a * type_count_ + b] = table_[b * type_count_ + a] = c;
  given_[a * type_count_ + b] = given_[b * type_count_ + a] = true;
}

bool PairCoefficients::is_set(int a, int b) const {
  return given_[a * type_count_ + b];
}

std::vector<int> PairCoefficients::resolve(Mixing mixing, const std::vector<MixRule>& rules) {
  std::vector<int> missing;
  for (int a = 0; a < type_count_; ++a) {
    if (!is_set(a, a)) missing.push_back(a);
  }
  if (!missing.empty()) return missing;
  auto mix = [mixing](double x, double y) {
    return mixing == Mixing::arithmetic ? 0.5 * (x + y) : std::sqrt(x * y);
  };
  for (int a = 0; a < type_count_; ++a) {
    for (int b = a + 1; b < type_count_; ++b) {
      if (is_set(a, b)) continue;
      const PairCoefficient& ca = at(a, a);
      const PairCoefficient& cb = at(b, b);
      PairCoefficient c;
      for (std::size_t k = 0; k < rules.size(); ++k) {
        const double x = ca.values[k], y = cb.values[k];
        c.values.push_back(rules[k] == MixRule::geometric ? std::sqrt(x * y) : mix(x, y));
      }
      c.cutoff = mix(ca.cutoff, cb.cutoff);
      table_[a * type_count_ + b] = table_[b * type_count_ + a] = c;
    }
  }
  return missing;
}

}  // namespace deli
