#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <string>
#include <utility>
#include <vector>

#include "forces/chunk_forces.hpp"
#include "forces/force_term.hpp"
#include "system/system.hpp"

namespace deli {

// What DihedralForce needs of a dihedral style: per dihedral type Params; evaluate(p, c, s,
// de_dphi) returns the energy at the torsion angle phi with cos(phi) = c, sin(phi) = s and
// sets de_dphi = dE/dphi. Both are 0 where phi is undefined (three atoms in a line).
template <class E>
concept DihedralEvaluator = std::default_initializable<typename E::Params> &&
    requires(const typename E::Params& p, double c, double s, double& de_dphi) {
  { E::evaluate(p, c, s, de_dphi) } -> std::convertible_to<double>;
};

// All dihedrals of one style (or of the types set in own_types, when the system has
// several); params indexed by dihedral type. phi is the IUPAC torsion angle of i-j-k-l
// (180 degrees trans), as in LAMMPS and OpenMM.
template <DihedralEvaluator Evaluator>
class DihedralForce final : public ForceTerm {
 public:
  using Params = typename Evaluator::Params;

  explicit DihedralForce(std::vector<Params> by_type, std::vector<char> own_types = {})
      : by_type_(std::move(by_type)), own_types_(std::move(own_types)) {}

  std::string name() const override { return "dihedral"; }

  // Chunks of consecutive dihedrals; energy and virial only when tallied (the force term's
  // contract).
  double compute(const System& system, const NeighborList&, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally) const override {
    return tally ? compute<true>(system, force, virial) : compute<false>(system, force, virial);
  }

 private:
  template <bool Tally>
  double compute(const System& system, std::vector<Vec3>& force, SymTensor& virial) const {
    const std::vector<Dihedral>& dihedrals = system.topology.dihedrals;
    return chunked_.run(dihedrals.size(), force, virial,
                        [&](std::size_t begin, std::size_t end, Vec3* f, SymTensor& w) {
                          double energy = 0.0;
                          for (std::size_t k = begin; k < end; ++k) {
                            const Dihedral& t = dihedrals[k];
                            if (!own_types_.empty() && !own_types_[t.type]) continue;
                            const double e = add_dihedral<Tally>(system, t, f, w);
                            if constexpr (Tally) energy += e;
                          }
                          return energy;
                        });
  }

  // One dihedral's forces added to f and (Tally) its virial to w; returns its energy.
  template <bool Tally>
  double add_dihedral(const System& system, const Dihedral& t, Vec3* f, SymTensor& w) const {
    const std::vector<Vec3>& x = system.particles.position;
    const Vec3 b1 = system.box.minimum_image(x[t.j] - x[t.i]);
    const Vec3 b2 = system.box.minimum_image(x[t.k] - x[t.j]);
    const Vec3 b3 = system.box.minimum_image(x[t.l] - x[t.k]);
    const Vec3 m = cross(b1, b2), n = cross(b2, b3);
    const double m2 = norm2(m), n2 = norm2(n), rb = norm(b2);
    // Where three atoms are in a line phi is undefined: LAMMPS takes the inverse lengths
    // as 0 there (cos = sin = 0, no force), and so do we, so that both engines agree.
    const double inv_m2 = m2 > 0.0 ? 1.0 / m2 : 0.0, inv_n2 = n2 > 0.0 ? 1.0 / n2 : 0.0;
    const double inv_mn = std::sqrt(inv_m2 * inv_n2);
    const double c = std::clamp(dot(m, n) * inv_mn, -1.0, 1.0);
    const double s = rb * dot(b1, n) * inv_mn;
    double g;  // dE/dphi
    const double energy = Evaluator::evaluate(by_type_[t.type], c, s, g);
    // dphi/dx (Bekker, for phi = atan2(|b2| b1.n, m.n)); F = -g dphi/dx.
    const Vec3 dphi_i = m * (-rb * inv_m2), dphi_l = n * (rb * inv_n2);
    const double rb2 = rb * rb;
    const double c1 = rb2 > 0.0 ? dot(b1, b2) / rb2 : 0.0;
    const double c3 = rb2 > 0.0 ? dot(b3, b2) / rb2 : 0.0;
    const Vec3 f_i = dphi_i * -g, f_l = dphi_l * -g;
    const Vec3 f_j = f_i * (-c1 - 1.0) + f_l * c3;
    const Vec3 f_k = f_l * (-c3 - 1.0) + f_i * c1;
    f[t.i] += f_i;
    f[t.j] += f_j;
    f[t.k] += f_k;
    f[t.l] += f_l;
    if constexpr (Tally) {
      // Positions relative to j: -b1, b2 and b2 + b3.
      w.add_outer(b1 * -1.0, f_i);
      w.add_outer(b2, f_k);
      w.add_outer(b2 + b3, f_l);
    }
    return energy;
  }

  std::vector<Params> by_type_;
  std::vector<char> own_types_;       // empty: every type
  mutable ChunkedForceLoop chunked_;  // scratch of compute()
};

}  // namespace deli
