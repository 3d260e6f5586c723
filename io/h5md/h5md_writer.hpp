#pragma once

#include <hdf5.h>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "h5md/h5_handle.hpp"
#include "h5md/trajectory_spec.hpp"
#include "simulation/observer.hpp"

namespace deli {

// Where a trajectory continues: a run restarted from a checkpoint at `step` appends to the
// existing file, dropping its frames after `step` (the restarted run writes them again).
struct TrajectoryContinuation {
  std::int64_t step = -1;  // -1: a new file
};

// An H5MD 1.1 trajectory (HDF5 C API): /h5md metadata, /particles/all with position,
// velocity, force and image as time series (step, time, value), species, mass, id, the
// hard-sphere diameters (when there are hard spheres) and the box (edges as a D x D matrix
// series, as MDAnalysis reads them), /observables for the thermo quantities and constraint
// statistics at every frame (MDAnalysis reads observables by frame index, so every
// observable has one entry per frame), /connectivity/bonds and /connectivity/rods (pairs of
// particle ids), and the input under /parameters. Series sampled at the position's frames
// share its step and time datasets (hard links), extended once per frame.
// Series are chunked, compressed and extended frame by frame; the file is flushed after
// every frame, so a run killed at any moment leaves every frame written before.
class H5mdWriter final : public Observer {
 public:
  H5mdWriter(const TrajectorySpec& spec, const System& system, const std::string& input_text,
             const std::string& author,
             const std::vector<std::pair<std::int32_t, std::int32_t>>& rods = {},
             bool hard_spheres = false, TrajectoryContinuation continuation = {});
  ~H5mdWriter() override;
  H5mdWriter(const H5mdWriter&) = delete;
  H5mdWriter& operator=(const H5mdWriter&) = delete;

  bool wants_frame(std::int64_t step) const override { return step % spec_.every == 0; }
  bool wants_shadow_energy() const override { return true; }
  void on_frame(const System& system, const ThermoSample& sample,
                const std::vector<Vec3>& forces) override;
  void on_finish(const System&) override;
  std::int64_t frames() const { return frames_; }

 private:
  struct Series {
    H5Handle group, step, time, value;
  };
  // A new time series; with `clock`, its step and time are hard links to clock's.
  Series make_series(hid_t parent, const std::string& name, hid_t type,
                     const std::vector<hsize_t>& frame_shape, const Series* clock = nullptr);
  void create(const System& system, const std::string& input_text, const std::string& author,
              const std::vector<std::pair<std::int32_t, std::int32_t>>& rods, bool hard_spheres);
  void reopen(const System& system, std::int64_t step);
  // Opens an existing series and cuts it back to its frames up to `step`.
  Series continue_series(hid_t parent, const std::string& name, std::int64_t step);
  void append(Series& s, std::int64_t step, double time, const void* data, hid_t memory_type,
              const std::vector<hsize_t>& frame_shape);
  // Closes every dataset and the file; throws when HDF5 could not write what it cached.
  void close();

  TrajectorySpec spec_;
  H5Handle file_;
  Series position_, velocity_, force_, image_, edges_;
  std::map<std::string, Series> observables_;
  H5Handle observables_group_;
  std::int64_t frames_ = 0;
  std::size_t atoms_ = 0;
  // A frame's rows in the input's order (system/particle_order.hpp), once the run has sorted.
  std::vector<Vec3> listed_vectors_;
  std::vector<std::array<int, 3>> listed_images_;
};

}  // namespace deli
