#include <cmath>

#include "bonded/bond_force.hpp"
#include "bonded/bonded_style.hpp"

namespace deli {

namespace {

// Kremer-Grest FENE (LAMMPS bond_style fene): -K R0^2/2 ln(1 - (r/R0)^2), plus the WCA
// repulsion 4 eps [(sig/r)^12 - (sig/r)^6] + eps for r < 2^(1/6) sig. Undefined from
// r = R0 on: evaluate() returns false there and the bond loop reports the bond.
struct FeneBond {
  struct Params {
    double k = 0, r0 = 0, epsilon = 0, sigma = 0;
  };
  template <bool kEnergy = true>
  static bool evaluate(const Params& p, double r2, double& f_over_r, double& energy) {
    const double r0sq = p.r0 * p.r0;
    const double log_arg = 1.0 - r2 / r0sq;
    if (log_arg <= 0.0) return false;
    f_over_r = -p.k / log_arg;
    if constexpr (kEnergy) energy = -0.5 * p.k * r0sq * std::log(log_arg);
    const double sigma2 = p.sigma * p.sigma;
    if (r2 < 1.2599210498948732 * sigma2) {  // 2^(1/3) sigma^2
      const double sr2 = sigma2 / r2;
      const double sr6 = sr2 * sr2 * sr2;
      f_over_r += 48.0 * p.epsilon * sr6 * (sr6 - 0.5) / r2;
      if constexpr (kEnergy) energy += 4.0 * p.epsilon * sr6 * (sr6 - 1.0) + p.epsilon;
    }
    return true;
  }
  static double second_derivative(const Params& p, double r2) {
    const double r0sq = p.r0 * p.r0;
    const double log_arg = 1.0 - r2 / r0sq;
    double d2 = p.k * (1.0 + r2 / r0sq) / (log_arg * log_arg);
    const double sigma2 = p.sigma * p.sigma;
    if (r2 < 1.2599210498948732 * sigma2) {
      const double sr2 = sigma2 / r2;
      const double sr6 = sr2 * sr2 * sr2;
      d2 += 4.0 * p.epsilon * (156.0 * sr6 * sr6 - 42.0 * sr6) / r2;
    }
    return d2;
  }
};
static_assert(BondEvaluator<FeneBond>);

}  // namespace

const BondedStyle& fene_bond_style() {
  using Check = StyleCoefficient::Check;
  static const BondedStyle style{
      BondedKind::bond,
      "fene",
      {{"k", Check::positive}, {"r0", Check::positive}, {"epsilon"}, {"sigma", Check::positive}},
      "fene bond coefficients K R0 epsilon sigma",
      [](const std::vector<std::vector<double>>& by_type,
         std::vector<char> own_types) -> std::unique_ptr<ForceTerm> {
        std::vector<FeneBond::Params> params;
        for (const std::vector<double>& c : by_type) params.push_back({c[0], c[1], c[2], c[3]});
        return std::make_unique<BondForce<FeneBond>>("bond", std::move(params),
                                                     std::move(own_types));
      },
      "-0.5*k*r0^2*log(1 - (r/r0)^2) + step(2^(1/6)*sigma - r)*(4*epsilon*((sigma/r)^12 - "
      "(sigma/r)^6) + epsilon)",
      "fene"};
  return style;
}

}  // namespace deli
