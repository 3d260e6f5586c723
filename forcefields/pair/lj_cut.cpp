#include <cmath>

#include "pair/lennard_jones.hpp"
#include "pair/pair_style.hpp"

namespace deli {

// lj/cut (this file) and wca (wca.cpp) share the 12-6 evaluator and these functions.
double lj_energy(const std::vector<double>& c, double r) {
  const double sr6 = std::pow(c[1] / r, 6);
  return 4.0 * c[0] * (sr6 * sr6 - sr6);
}

double lj_force(const std::vector<double>& c, double r) {
  const double sr6 = std::pow(c[1] / r, 6);
  return std::abs(24.0 * c[0] * (2.0 * sr6 * sr6 - sr6) / r);
}

std::unique_ptr<ForceTerm> lj_term(const PairCoefficients& c, bool shift, double max_cutoff,
                                   std::vector<ScaledPair> scaled) {
  std::vector<LennardJones::Params> table;
  for (int a = 0; a < c.type_count(); ++a) {
    for (int b = 0; b < c.type_count(); ++b) {
      const PairCoefficient& p = c.at(a, b);
      table.push_back(LennardJones::make(p.values[0], p.values[1], p.cutoff));
    }
  }
  return std::make_unique<PairForce<LennardJones>>("pair", c.type_count(), std::move(table), shift,
                                                   max_cutoff, std::move(scaled));
}

const PairStyle& lj_cut_pair_style() {
  using Check = StyleCoefficient::Check;
  static const PairStyle style{"lj/cut",
                               {{"epsilon", Check::non_negative}, {"sigma", Check::positive}},
                               {MixRule::geometric, MixRule::chosen},
                               "lj/cut coefficients are epsilon sigma [cutoff]",
                               nullptr,
                               false,
                               lj_energy,
                               lj_force,
                               lj_term,
                               "4*epsilon*((sigma/r)^12 - (sigma/r)^6)",
                               "lj/cut"};
  return style;
}

}  // namespace deli
