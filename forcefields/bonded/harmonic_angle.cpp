#include "bonded/harmonic_angle.hpp"

#include <algorithm>
#include <cmath>

#include "system/system.hpp"

namespace deli {

double HarmonicAngle::compute(const System& system, const NeighborList&, std::vector<Vec3>& force,
                              SymTensor& virial, bool /*tally*/) const {
  const std::vector<Vec3>& x = system.particles.position;
  double energy = 0.0;
  for (const Angle& a : system.topology.angles) {
    const Params& p = by_type_[a.type];
    const Vec3 d1 = system.box.minimum_image(x[a.i] - x[a.j]);
    const Vec3 d2 = system.box.minimum_image(x[a.k] - x[a.j]);
    const double r1sq = norm2(d1), r2sq = norm2(d2);
    const double r1 = std::sqrt(r1sq), r2 = std::sqrt(r2sq);
    const double c = std::clamp(dot(d1, d2) / (r1 * r2), -1.0, 1.0);
    // d(theta)/d(cos) = -1/sin is singular for a straight angle; LAMMPS bounds sin below
    // by 0.001 there, and so do we, so that both engines give the same forces.
    const double s = 1.0 / std::max(std::sqrt(1.0 - c * c), 0.001);
    const double dtheta = std::acos(c) - p.theta0;
    const double tk = p.k * dtheta;
    energy += tk * dtheta;
    const double g = -2.0 * tk * s;
    const double a11 = g * c / r1sq, a12 = -g / (r1 * r2), a22 = g * c / r2sq;
    const Vec3 f1 = d1 * a11 + d2 * a12;
    const Vec3 f3 = d2 * a22 + d1 * a12;
    force[a.i] += f1;
    force[a.j] -= f1 + f3;
    force[a.k] += f3;
    virial.add_outer(d1, f1);
    virial.add_outer(d2, f3);
  }
  return energy;
}

}  // namespace deli
