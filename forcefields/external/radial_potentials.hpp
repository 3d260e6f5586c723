#pragma once

#include <vector>

#include "forces/force_term.hpp"
#include "system/system.hpp"

namespace deli {

// Central potentials of the paper's examples, one per particle about a centre c, in
// s = |x - c|^2 (positions as stored: use them with open boundaries):
//   inverse square  V = A / s                       (outward pull of the spring and sphere)
//   polynomial      V = sum_k a_k s^k               (the nonlinear oscillator: s (s - 1)^2 =
//                                                    s^3 - 2 s^2 + s, a = [0, 1, -2, 1])
class RadialPotential final : public ForceTerm {
 public:
  enum class Kind { inverse_square, polynomial };
  RadialPotential(Kind kind, Vec3 center, std::vector<double> coefficients)
      : kind_(kind), center_(center), a_(std::move(coefficients)) {}

  std::string name() const override { return "external"; }
  double compute(const System& system, const NeighborList&, std::vector<Vec3>& force, SymTensor&,
                 bool) const override {
    const Particles& p = system.particles;
    double energy = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec3 d = p.position[i] - center_;
      const double s = norm2(d);
      double v = 0.0, dv_ds = 0.0;
      if (kind_ == Kind::inverse_square) {
        v = a_[0] / s;
        dv_ds = -a_[0] / (s * s);
      } else {
        double power = 1.0;  // s^k
        for (std::size_t k = 0; k < a_.size(); ++k) {
          v += a_[k] * power;
          if (k + 1 < a_.size()) dv_ds += static_cast<double>(k + 1) * a_[k + 1] * power;
          power *= s;
        }
      }
      energy += v;
      force[i] -= d * (2.0 * dv_ds);  // dV/dx = dV/ds 2 (x - c)
    }
    return energy;
  }

 private:
  Kind kind_;
  Vec3 center_;
  std::vector<double> a_;
};

}  // namespace deli
