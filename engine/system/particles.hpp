#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/vec3.hpp"

namespace deli {

// Per-particle state as parallel contiguous arrays (index = internal particle index).
// `id` is the user's atom id (LAMMPS data file ids), used in every message.
struct Particles {
  std::vector<Vec3> position;
  std::vector<Vec3> velocity;
  std::vector<double> mass;
  std::vector<double> radius;
  std::vector<int> type;  // 0-based type index
  std::vector<std::int64_t> id;
  std::vector<std::int64_t> molecule;  // 0 when the particle belongs to no molecule
  std::vector<std::array<int, 3>> image;
  // The index each particle had in the input (data file or builder), once the particles have
  // been put in another order (system/particle_order.hpp); empty while they are in the
  // input's order. Outputs list the particles in the input's order.
  std::vector<std::int32_t> origin;

  std::size_t size() const { return position.size(); }
  void resize(std::size_t n);
};

}  // namespace deli
