#include "bonded/angle_force.hpp"
#include "bonded/bonded_style.hpp"

namespace deli {

namespace {

// E = K [1 + cos(theta)] (LAMMPS angle_style cosine): the bending stiffness of
// semiflexible Kremer-Grest chains, least energy for a straight chain (theta = 180).
struct CosineAngle {
  struct Params {
    double k = 0;
  };
  static double evaluate(const Params& p, double c, double& de_dcos) {
    de_dcos = p.k;
    return p.k * (1.0 + c);
  }
};
static_assert(AngleEvaluator<CosineAngle>);

}  // namespace

const BondedStyle& cosine_angle_style() {
  static const BondedStyle style{BondedKind::angle,
                                 "cosine",
                                 {{"k"}},
                                 "cosine angle coefficients K",
                                 [](const std::vector<std::vector<double>>& by_type,
                                    std::vector<char> own_types) -> std::unique_ptr<ForceTerm> {
                                   std::vector<CosineAngle::Params> params;
                                   for (const std::vector<double>& c : by_type)
                                     params.push_back({c[0]});
                                   return std::make_unique<AngleForce<CosineAngle>>(
                                       std::move(params), std::move(own_types));
                                 },
                                 "k*(1 + cos(theta))",
                                 "cosine"};
  return style;
}

}  // namespace deli
