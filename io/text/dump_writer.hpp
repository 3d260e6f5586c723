#pragma once

#include <cstdint>
#include <fstream>
#include <string>

#include "simulation/observer.hpp"

namespace deli {

// Text trajectories for quick looks: LAMMPS `dump custom` layout (id type x y z ix iy iz
// vx vy vz, which OVITO reads) or extended XYZ (Lattice, Origin, pbc, Time, Step; species,
// position, id and the hard-sphere radius; ASE and OVITO read the box from it). A frame
// every `every` steps, flushed as written.
// The extended XYZ species of a 0-based type: the element whose atomic number is the type
// number (type 1 "H", 2 "He", ...), the only names ASE accepts; throws past 118.
const char* xyz_species(int type);

class DumpWriter final : public Observer {
 public:
  enum class Format { lammps, xyz };
  // continue_from >= 0: a restart at that step appends to the file, cut back to the frames
  // up to it. hard_spheres: the XYZ frames carry the particles' radii.
  DumpWriter(const std::string& path, Format format, std::int64_t every,
             std::int64_t continue_from = -1, bool hard_spheres = false);

  bool wants_frame(std::int64_t step) const override { return step % every_ == 0; }
  void on_frame(const System& system, const ThermoSample&, const std::vector<Vec3>&) override;
  // Closes the file, throwing when it could not be written.
  void on_finish(const System&) override;

 private:
  std::string path_;
  std::ofstream out_;
  std::uintmax_t written_ = 0;  // bytes of whole records in the file
  Format format_;
  std::int64_t every_;
  bool radii_;
};

}  // namespace deli
