#pragma once

#include <cstdint>
#include <string>

namespace deli {

// [output] trajectory: what an H5MD trajectory holds and how often.
struct TrajectorySpec {
  std::string file;  // "" = no trajectory
  std::int64_t every = 1000;
  bool velocities = true;
  bool images = true;
  int compression = 4;  // deflate level, 0: none
  bool forces = false;  // the force field's forces (constraint impulses are not forces)
};

}  // namespace deli
