#pragma once

#include "forces/force_term.hpp"
#include "system/system.hpp"

namespace deli {

// A uniform field: F_i = m_i g, V = -sum m_i g . x_i (positions as stored: use it along
// open axes). Like LAMMPS' fix gravity it adds nothing to the virial.
class Gravity final : public ForceTerm {
 public:
  explicit Gravity(Vec3 g) : g_(g) {}
  std::string name() const override { return "external"; }
  // A uniform field has no curvature.
  bool pair_hessians(const System&, const NeighborList&, const std::vector<char>&,
                     std::vector<PairHessian>&) const override {
    return true;
  }
  double compute(const System& system, const NeighborList&, std::vector<Vec3>& force, SymTensor&,
                 bool) const override {
    const Particles& p = system.particles;
    double energy = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      force[i] += g_ * p.mass[i];
      energy -= p.mass[i] * dot(g_, p.position[i]);
    }
    return energy;
  }

 private:
  Vec3 g_;
};

}  // namespace deli
