#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "simulation/observer.hpp"

namespace deli {

class Integrator;

// Everything a run needs to continue bit for bit: positions (as wrapped), velocities,
// image flags, step and time, and the positions of the last neighbour-list build (the
// pair order, hence the rounding, depends on them). Runs draw no random numbers after the
// start, so there is no generator state to keep.
struct Checkpoint {
  std::int64_t step = 0;
  double time = 0;
  std::vector<std::int64_t> id;
  std::vector<Vec3> position, velocity, build_positions;
  std::vector<std::array<int, 3>> image;
};

// Written aside (PATH.partial) and renamed over PATH: a crash mid-write leaves the previous
// checkpoint intact.
void write_checkpoint(const std::string& path, const System& system,
                      const std::vector<Vec3>& build_positions);
// Refuses a missing, truncated or foreign file with a message naming it.
Checkpoint read_checkpoint(const std::string& path);
// Puts a checkpoint's state into a system built from the same input; the atoms must match.
void apply_checkpoint(const Checkpoint& checkpoint, System& system, const std::string& path);

// A checkpoint every `every` steps during a run.
class CheckpointWriter final : public Observer {
 public:
  CheckpointWriter(std::string path, std::int64_t every, const Integrator& integrator)
      : path_(std::move(path)), every_(every), integrator_(integrator) {}
  void on_step(const System& system) override;

 private:
  std::string path_;
  std::int64_t every_;
  const Integrator& integrator_;
};

}  // namespace deli
