#include <algorithm>
#include <cmath>

#include "bonded/angle_force.hpp"
#include "bonded/bonded_style.hpp"

namespace deli {

namespace {

// E = K (theta - theta0)^2 (LAMMPS angle_style harmonic: no factor 1/2; theta0 given in
// degrees, held in radians).
struct HarmonicAngle {
  struct Params {
    double k = 0, theta0 = 0;
  };
  static double evaluate(const Params& p, double c, double& de_dcos) {
    // d(theta)/d(cos) = -1/sin is singular for a straight angle; LAMMPS bounds sin below
    // by 0.001 there, and so do we, so that both engines give the same forces.
    const double s = 1.0 / std::max(std::sqrt(1.0 - c * c), 0.001);
    const double dtheta = std::acos(c) - p.theta0;
    const double tk = p.k * dtheta;
    de_dcos = -2.0 * tk * s;
    return tk * dtheta;
  }
};
static_assert(AngleEvaluator<HarmonicAngle>);

}  // namespace

const BondedStyle& harmonic_angle_style() {
  static const BondedStyle style{BondedKind::angle,
                                 "harmonic",
                                 {{"k"}, {"theta0", StyleCoefficient::Check::any, true}},
                                 "harmonic angle coefficients K theta0",
                                 [](const std::vector<std::vector<double>>& by_type,
                                    std::vector<char> own_types) -> std::unique_ptr<ForceTerm> {
                                   std::vector<HarmonicAngle::Params> params;
                                   for (const std::vector<double>& c : by_type)
                                     params.push_back({c[0], c[1]});
                                   return std::make_unique<AngleForce<HarmonicAngle>>(
                                       std::move(params), std::move(own_types));
                                 },
                                 "k*(theta - theta0)^2",
                                 "harmonic"};
  return style;
}

}  // namespace deli
