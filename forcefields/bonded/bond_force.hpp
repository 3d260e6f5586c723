#pragma once

#include <string>
#include <utility>
#include <vector>

#include "bonded/bond_evaluator.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "forces/chunk_forces.hpp"
#include "forces/force_term.hpp"
#include "system/system.hpp"

namespace deli {

// All bonds of one style (or of the types set in own_types, when the system has several);
// params indexed by bond type.
template <BondEvaluator Evaluator>
class BondForce final : public ForceTerm {
 public:
  using Params = typename Evaluator::Params;

  BondForce(std::string name, std::vector<Params> by_type, std::vector<char> own_types = {})
      : name_(std::move(name)), by_type_(std::move(by_type)), own_types_(std::move(own_types)) {}

  std::string name() const override { return name_; }

  bool pair_hessians(const System& system, const NeighborList&, const std::vector<char>& mask,
                     std::vector<PairHessian>& out) const override {
    const std::vector<Vec3>& x = system.particles.position;
    for (const Bond& b : system.topology.bonds) {
      if (!mask.empty() && !mask[b.i] && !mask[b.j]) continue;
      if (!own_types_.empty() && !own_types_[b.type]) continue;
      const Vec3 d = system.box.minimum_image(x[b.i] - x[b.j]);
      const double r2 = norm2(d);
      double f_over_r = 0.0, e = 0.0;
      if (!Evaluator::template evaluate<false>(by_type_[b.type], r2, f_over_r, e)) {
        stretched(system, b, d);
      }
      out.push_back({b.i, b.j,
                     pair_hessian_block(d, r2, f_over_r,
                                        Evaluator::second_derivative(by_type_[b.type], r2))});
    }
    return true;
  }

  // Energy and virial only when tallied (the force term's contract): summing them on every
  // step, through the caller's virial in memory, was half of a chain melt's bond time.
  // Chunks of consecutive bonds.
  double compute(const System& system, const NeighborList&, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally) const override {
    return tally ? compute<true>(system, force, virial) : compute<false>(system, force, virial);
  }

 private:
  template <bool Tally>
  double compute(const System& system, std::vector<Vec3>& force, SymTensor& virial) const {
    const std::vector<Vec3>& x = system.particles.position;
    const std::vector<Bond>& bonds = system.topology.bonds;
    return chunked_.run(
        bonds.size(), force, virial,
        [&](std::size_t begin, std::size_t end, Vec3* f, SymTensor& w) {
          double energy = 0.0;
          for (std::size_t k = begin; k < end; ++k) {
            const Bond& b = bonds[k];
            if (!own_types_.empty() && !own_types_[b.type]) continue;
            const Vec3 d = system.box.minimum_image(x[b.i] - x[b.j]);
            double f_over_r = 0.0, e = 0.0;
            if (!Evaluator::template evaluate<Tally>(by_type_[b.type], norm2(d), f_over_r, e)) {
              stretched(system, b, d);
            }
            const Vec3 fb = d * f_over_r;
            f[b.i] += fb;
            f[b.j] -= fb;
            if constexpr (Tally) {
              energy += e;
              w.add_outer(d, fb);
            }
          }
          return energy;
        });
  }

  // A bond beyond where its potential is defined (FENE past r0) stops the run.
  [[noreturn]] void stretched(const System& system, const Bond& b, const Vec3& d) const {
    throw SimulationError(
        "step " + std::to_string(system.step) + ": " + name_ + " bond between atoms " +
        std::to_string(system.particles.id[b.i]) + " and " +
        std::to_string(system.particles.id[b.j]) +
        " is stretched to r = " + std::to_string(norm(d)) +
        ", beyond where the potential of bond type " + std::to_string(b.type + 1) + " is defined" +
        (system.step == 0 ? std::string(" already at the start: give that type a larger "
                                        "r0 in [forcefield.bond] coeffs, or start from "
                                        "shorter bonds")
                          : std::string("; reduce the timestep or start from a relaxed "
                                        "configuration")));
  }

  std::string name_;
  std::vector<Params> by_type_;
  std::vector<char> own_types_;       // empty: every type
  mutable ChunkedForceLoop chunked_;  // scratch of compute()
};

}  // namespace deli
