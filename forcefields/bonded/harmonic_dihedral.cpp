#include "bonded/bonded_style.hpp"
#include "bonded/dihedral_force.hpp"

namespace deli {

namespace {

// E = K [1 + d cos(n phi)] (LAMMPS dihedral_style harmonic): d = +1 or -1, n a whole
// number from 0. cos(n phi) and sin(n phi) by LAMMPS' recursion from cos and sin of phi.
struct HarmonicDihedral {
  struct Params {
    double k = 0, d = 1;
    int n = 0;
  };
  static double evaluate(const Params& p, double c, double s, double& de_dphi) {
    double cos_n = 1.0, sin_n = 0.0;
    for (int i = 0; i < p.n; ++i) {
      const double next = cos_n * c - sin_n * s;
      sin_n = cos_n * s + sin_n * c;
      cos_n = next;
    }
    de_dphi = -p.k * p.d * p.n * sin_n;
    return p.k * (1.0 + p.d * cos_n);
  }
};
static_assert(DihedralEvaluator<HarmonicDihedral>);

}  // namespace

const BondedStyle& harmonic_dihedral_style() {
  using Check = StyleCoefficient::Check;
  static const BondedStyle style{
      BondedKind::dihedral,
      "harmonic",
      {{"k"}, {"d", Check::sign}, {"n", Check::non_negative_integer}},
      "harmonic dihedral coefficients K d n",
      [](const std::vector<std::vector<double>>& by_type,
         std::vector<char> own_types) -> std::unique_ptr<ForceTerm> {
        std::vector<HarmonicDihedral::Params> params;
        for (const std::vector<double>& c : by_type) {
          params.push_back({c[0], c[1], static_cast<int>(c[2])});
        }
        return std::make_unique<DihedralForce<HarmonicDihedral>>(std::move(params),
                                                                 std::move(own_types));
      },
      // OpenMM's theta is the same IUPAC angle; cos(n theta) is even in it, so its sign
      // convention cannot matter, and d needs no phase (PeriodicTorsionForce's phase would
      // be 0 for d = +1, 180 degrees for d = -1).
      "k*(1 + d*cos(n*theta))",
      "harmonic"};
  return style;
}

}  // namespace deli
