#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "simulation/observer.hpp"

namespace deli {

class Integrator;

// Everything a run needs to continue bit for bit: positions (as wrapped), velocities,
// image flags, step and time, the positions of the last neighbour-list build (the pair
// order, hence the rounding, depends on them) and the integrator's own state (statistics
// accumulated since the last samples, the linearisation point of linearised constraints).
// Runs draw no random numbers after the start, so there is no generator state to keep.
// A checkpoint is taken after its step's thermo row and frames are written.
struct Checkpoint {
  std::int64_t step = 0;
  double time = 0;
  std::vector<std::int64_t> id;
  std::vector<Vec3> position, velocity, build_positions;
  std::vector<std::array<int, 3>> image;
  std::vector<double> integrator_state;  // opaque: the integrator's saved_state()
  std::uint64_t fingerprint = 0;         // system_fingerprint() of the run that wrote it
};

// Written aside (PATH.partial), closed, fsync'd, read back and compared, then renamed over
// PATH: a crash or a full disk mid-write leaves the previous checkpoint intact. Every dataset
// carries a checksum. Refuses (SimulationError) to replace anything but a regular file.
void write_checkpoint(const std::string& path, const System& system,
                      const std::vector<Vec3>& build_positions,
                      const std::vector<double>& integrator_state = {},
                      std::uint64_t fingerprint = 0);
void write_checkpoint(const std::string& path, const System& system, const Integrator& integrator,
                      std::uint64_t fingerprint = 0);
// Refuses a missing, truncated, damaged (checksums) or inconsistent file (negative step,
// non-finite positions) with a message naming it.
Checkpoint read_checkpoint(const std::string& path);
// Puts a checkpoint's state into a system built from the same input; the atoms must match,
// and the system's fingerprint where one is given.
void apply_checkpoint(const Checkpoint& checkpoint, System& system, const std::string& path,
                      std::optional<std::uint64_t> fingerprint = std::nullopt);

// A checkpoint every `every` steps during a run.
class CheckpointWriter final : public Observer {
 public:
  CheckpointWriter(std::string path, std::int64_t every, const Integrator& integrator,
                   std::uint64_t fingerprint = 0)
      : path_(std::move(path)), every_(every), integrator_(integrator), fingerprint_(fingerprint) {}
  void on_step_complete(const System& system) override;

 private:
  std::string path_;
  std::int64_t every_;
  const Integrator& integrator_;
  std::uint64_t fingerprint_;
};

}  // namespace deli
