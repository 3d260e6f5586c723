#include <cmath>

#include "pair/pair_style.hpp"

namespace deli {

double lj_energy(const std::vector<double>& c, double r);
double lj_force(const std::vector<double>& c, double r);
std::unique_ptr<ForceTerm> lj_term(const PairCoefficients& c, bool shift, double max_cutoff,
                                   std::vector<ScaledPair> scaled);

// Weeks-Chandler-Andersen: lj/cut cut at the minimum, 2^(1/6) sigma, and shifted there
// (LAMMPS: lj/cut with that cutoff and pair_modify shift yes).
const PairStyle& wca_pair_style() {
  using Check = StyleCoefficient::Check;
  static const PairStyle style{
      "wca",
      {{"epsilon", Check::non_negative}, {"sigma", Check::positive}},
      {MixRule::geometric, MixRule::chosen},
      "lj/cut coefficients are epsilon sigma [cutoff]",
      [](const std::vector<double>& c) { return std::pow(2.0, 1.0 / 6.0) * c[1]; },
      true,
      lj_energy,
      lj_force,
      lj_term,
      "4*epsilon*((sigma/r)^12 - (sigma/r)^6)",
      "lj/cut"};
  return style;
}

}  // namespace deli
