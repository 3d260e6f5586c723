#pragma once

#include <string>
#include <vector>

#include "system/box.hpp"
#include "system/particles.hpp"
#include "system/topology.hpp"

namespace deli {

// Per-atom-type data; a type's mass and radius are copied to its particles.
struct AtomType {
  double mass = 1.0;
  double radius = 0.5;
};

struct System {
  Box box;
  Particles particles;
  Topology topology;
  std::vector<AtomType> atom_types;
  double time = 0.0;
  std::int64_t step = 0;
};

}  // namespace deli
