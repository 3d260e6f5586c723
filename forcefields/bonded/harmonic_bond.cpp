#include <cmath>

#include "bonded/bond_force.hpp"
#include "bonded/bonded_style.hpp"

namespace deli {

namespace {

// E = K (r - r0)^2 (LAMMPS bond_style harmonic: no factor 1/2).
struct HarmonicBond {
  struct Params {
    double k = 0, r0 = 0;
  };
  template <bool kEnergy = true>
  static bool evaluate(const Params& p, double r2, double& f_over_r, double& energy) {
    const double r = std::sqrt(r2);
    const double dr = r - p.r0;
    if constexpr (kEnergy) energy = p.k * dr * dr;
    f_over_r = r > 0.0 ? -2.0 * p.k * dr / r : 0.0;
    return true;
  }
  static double second_derivative(const Params& p, double /*r2*/) { return 2.0 * p.k; }
};
static_assert(BondEvaluator<HarmonicBond>);

}  // namespace

const BondedStyle& harmonic_bond_style() {
  static const BondedStyle style{BondedKind::bond,
                                 "harmonic",
                                 {{"k"}, {"r0", StyleCoefficient::Check::positive}},
                                 "harmonic bond coefficients K r0",
                                 [](const std::vector<std::vector<double>>& by_type,
                                    std::vector<char> own_types) -> std::unique_ptr<ForceTerm> {
                                   std::vector<HarmonicBond::Params> params;
                                   for (const std::vector<double>& c : by_type)
                                     params.push_back({c[0], c[1]});
                                   return std::make_unique<BondForce<HarmonicBond>>(
                                       "bond", std::move(params), std::move(own_types));
                                 },
                                 "k*(r - r0)^2",
                                 "harmonic"};
  return style;
}

}  // namespace deli
