#pragma once

#include <vector>

#include "forces/force_term.hpp"

namespace deli {

// E = K (theta - theta0)^2 (LAMMPS angle_style harmonic; theta0 given in degrees).
class HarmonicAngle final : public ForceTerm {
 public:
  struct Params {
    double k = 0, theta0 = 0;  // theta0 in radians
  };
  explicit HarmonicAngle(std::vector<Params> by_type) : by_type_(std::move(by_type)) {}

  std::string name() const override { return "angle"; }
  double compute(const System& system, const NeighborList& neighbors, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally) const override;

 private:
  std::vector<Params> by_type_;
};

}  // namespace deli
