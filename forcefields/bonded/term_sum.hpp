#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "forces/force_term.hpp"

namespace deli {

// Several terms reported as one (the bonds of a system whose bond types differ in style):
// energies, forces, virial and Hessian blocks are those of the parts, in order.
class TermSum final : public ForceTerm {
 public:
  explicit TermSum(std::string name) : name_(std::move(name)) {}
  void add(std::unique_ptr<ForceTerm> term) { parts_.push_back(std::move(term)); }

  std::string name() const override { return name_; }
  double neighbor_cutoff() const override {
    double cutoff = 0.0;
    for (const auto& p : parts_) cutoff = std::max(cutoff, p->neighbor_cutoff());
    return cutoff;
  }
  double compute(const System& system, const NeighborList& neighbors, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally) const override {
    double energy = 0.0;
    for (const auto& p : parts_) energy += p->compute(system, neighbors, force, virial, tally);
    return energy;
  }
  bool pair_hessians(const System& system, const NeighborList& neighbors,
                     const std::vector<char>& mask, std::vector<PairHessian>& out) const override {
    for (const auto& p : parts_) {
      if (!p->pair_hessians(system, neighbors, mask, out)) return false;
    }
    return true;
  }

 private:
  std::string name_;
  std::vector<std::unique_ptr<ForceTerm>> parts_;
};

}  // namespace deli
