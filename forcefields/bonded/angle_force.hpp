#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <string>
#include <utility>
#include <vector>

#include "core/parallel.hpp"
#include "forces/chunk_forces.hpp"
#include "forces/force_term.hpp"
#include "system/system.hpp"

namespace deli {

// What AngleForce needs of an angle style: per angle type Params; evaluate(p, c, de_dcos)
// returns the energy at cos(theta) = c and sets de_dcos = dE/d(cos theta).
template <class E>
concept AngleEvaluator = std::default_initializable<typename E::Params> &&
    requires(const typename E::Params& p, double c, double& de_dcos) {
  { E::evaluate(p, c, de_dcos) } -> std::convertible_to<double>;
};

// All angles of one style (or of the types set in own_types, when the system has several);
// params indexed by angle type.
template <AngleEvaluator Evaluator>
class AngleForce final : public ForceTerm {
 public:
  using Params = typename Evaluator::Params;

  explicit AngleForce(std::vector<Params> by_type, std::vector<char> own_types = {})
      : by_type_(std::move(by_type)), own_types_(std::move(own_types)) {}

  std::string name() const override { return "angle"; }

  // Chunks of consecutive angles.
  // Energy and virial only when tallied (the force term's contract).
  double compute(const System& system, const NeighborList&, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally) const override {
    return tally ? compute<true>(system, force, virial) : compute<false>(system, force, virial);
  }

 private:
  template <bool Tally>
  double compute(const System& system, std::vector<Vec3>& force, SymTensor& virial) const {
    const std::vector<Vec3>& x = system.particles.position;
    const std::vector<Angle>& angles = system.topology.angles;
    return chunked_.run(angles.size(), force, virial,
                        [&](std::size_t begin, std::size_t end, Vec3* f, SymTensor& w) {
                          double energy = 0.0;
                          for (std::size_t k = begin; k < end; ++k) {
                            const Angle& a = angles[k];
                            if (!own_types_.empty() && !own_types_[a.type]) continue;
                            const Vec3 d1 = system.box.minimum_image(x[a.i] - x[a.j]);
                            const Vec3 d2 = system.box.minimum_image(x[a.k] - x[a.j]);
                            const double r1sq = norm2(d1), r2sq = norm2(d2);
                            const double r1 = std::sqrt(r1sq), r2 = std::sqrt(r2sq);
                            const double cos_theta = std::clamp(dot(d1, d2) / (r1 * r2), -1.0, 1.0);
                            double g;  // dE/d(cos theta)
                            const double e = Evaluator::evaluate(by_type_[a.type], cos_theta, g);
                            const double a11 = g * cos_theta / r1sq, a12 = -g / (r1 * r2);
                            const double a22 = g * cos_theta / r2sq;
                            const Vec3 f1 = d1 * a11 + d2 * a12;
                            const Vec3 f3 = d2 * a22 + d1 * a12;
                            f[a.i] += f1;
                            f[a.j] -= f1 + f3;
                            f[a.k] += f3;
                            if constexpr (Tally) {
                              energy += e;
                              w.add_outer(d1, f1);
                              w.add_outer(d2, f3);
                            }
                          }
                          return energy;
                        });
  }

  std::vector<Params> by_type_;
  std::vector<char> own_types_;       // empty: every type
  mutable ChunkedForceLoop chunked_;  // scratch of compute()
};

}  // namespace deli
