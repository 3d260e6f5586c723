#pragma once

#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace deli {

struct System;
class NeighborList;

// One term of the potential energy (all pairs of one style, all bonds of one style...).
// compute() adds its forces and, when `tally`, its virial, and returns its energy (0 when
// not `tally`: most steps need forces only). One virtual call per term per step, never per
// pair.
class ForceTerm {
 public:
  virtual ~ForceTerm() = default;
  virtual std::string name() const = 0;
  // Largest interaction distance that must come from the neighbour list (0: none).
  virtual double neighbor_cutoff() const { return 0.0; }
  virtual double compute(const System& system, const NeighborList& neighbors,
                         std::vector<Vec3>& force, SymTensor& virial, bool tally) const = 0;
};

}  // namespace deli
