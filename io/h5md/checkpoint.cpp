#include "h5md/checkpoint.hpp"

#include <hdf5.h>

#include <cstdio>

#include "core/error.hpp"
#include "integrators/integrator.hpp"

namespace deli {

namespace {

template <class T>
void write_set(hid_t file, const char* name, hid_t type, const std::vector<hsize_t>& shape,
               const T* data, const std::string& path) {
  const hid_t space = H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr);
  const hid_t set = H5Dcreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t status = set < 0 ? -1 : H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  if (set >= 0) H5Dclose(set);
  H5Sclose(space);
  if (status < 0) throw SimulationError(path + ": could not write the checkpoint (disk full?)");
}

template <class T>
void read_set(hid_t file, const char* name, hid_t type, std::size_t count, T* data,
              const std::string& path) {
  const hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
  bool ok = set >= 0;
  if (ok) {
    const hid_t space = H5Dget_space(set);
    ok = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)) == count &&
         H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
    H5Sclose(space);
    H5Dclose(set);
  }
  if (!ok) {
    throw InputError(path + ": the checkpoint's '" + std::string(name) +
                     "' is missing or damaged; restart from an intact checkpoint");
  }
}

}  // namespace

void write_checkpoint(const std::string& path, const System& system, const Integrator& integrator) {
  write_checkpoint(path, system, integrator.forces().neighbors().positions_at_build(),
                   integrator.saved_state());
}

void write_checkpoint(const std::string& path, const System& system,
                      const std::vector<Vec3>& build_positions,
                      const std::vector<double>& integrator_state) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const std::string aside = path + ".partial";
  const hid_t file = H5Fcreate(aside.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw SimulationError(aside + ": cannot create the checkpoint file");
  const Particles& p = system.particles;
  const hsize_t n = p.size();
  const std::int64_t step = system.step;
  write_set(file, "step", H5T_NATIVE_INT64, {1}, &step, aside);
  write_set(file, "time", H5T_NATIVE_DOUBLE, {1}, &system.time, aside);
  write_set(file, "id", H5T_NATIVE_INT64, {n}, p.id.data(), aside);
  write_set(file, "position", H5T_NATIVE_DOUBLE, {n, 3}, p.position.data(), aside);
  write_set(file, "velocity", H5T_NATIVE_DOUBLE, {n, 3}, p.velocity.data(), aside);
  write_set(file, "image", H5T_NATIVE_INT, {n, 3}, p.image.data(), aside);
  write_set(file, "neighbor_build_positions", H5T_NATIVE_DOUBLE, {build_positions.size(), 3},
            build_positions.data(), aside);
  write_set(file, "integrator_state", H5T_NATIVE_DOUBLE, {integrator_state.size()},
            integrator_state.data(), aside);
  if (H5Fclose(file) < 0 || std::rename(aside.c_str(), path.c_str()) != 0) {
    throw SimulationError(path + ": could not complete the checkpoint (disk full?)");
  }
}

Checkpoint read_checkpoint(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    throw InputError(path + ": not a deli checkpoint (missing, truncated or not HDF5)");
  }
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw InputError(path + ": the checkpoint cannot be opened (damaged?)");
  Checkpoint c;
  try {
    read_set(file, "step", H5T_NATIVE_INT64, 1, &c.step, path);
    read_set(file, "time", H5T_NATIVE_DOUBLE, 1, &c.time, path);
    const hid_t ids = H5Dopen2(file, "id", H5P_DEFAULT);
    if (ids < 0) throw InputError(path + ": not a deli checkpoint (no 'id')");
    const hid_t space = H5Dget_space(ids);
    const auto n = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space));
    H5Sclose(space);
    H5Dclose(ids);
    c.id.resize(n);
    c.position.resize(n);
    c.velocity.resize(n);
    c.image.resize(n);
    c.build_positions.resize(n);
    read_set(file, "id", H5T_NATIVE_INT64, n, c.id.data(), path);
    read_set(file, "position", H5T_NATIVE_DOUBLE, 3 * n, c.position.data(), path);
    read_set(file, "velocity", H5T_NATIVE_DOUBLE, 3 * n, c.velocity.data(), path);
    read_set(file, "image", H5T_NATIVE_INT, 3 * n, c.image.data(), path);
    read_set(file, "neighbor_build_positions", H5T_NATIVE_DOUBLE, 3 * n, c.build_positions.data(),
             path);
    const hid_t state = H5Dopen2(file, "integrator_state", H5P_DEFAULT);
    if (state < 0) throw InputError(path + ": the checkpoint has no 'integrator_state'");
    const hid_t state_space = H5Dget_space(state);
    c.integrator_state.resize(static_cast<std::size_t>(H5Sget_simple_extent_npoints(state_space)));
    H5Sclose(state_space);
    H5Dclose(state);
    read_set(file, "integrator_state", H5T_NATIVE_DOUBLE, c.integrator_state.size(),
             c.integrator_state.data(), path);
  } catch (...) {
    H5Fclose(file);
    throw;
  }
  H5Fclose(file);
  return c;
}

void apply_checkpoint(const Checkpoint& c, System& system, const std::string& path) {
  Particles& p = system.particles;
  if (c.id != p.id) {
    throw InputError(path + ": the checkpoint holds " + std::to_string(c.id.size()) +
                     " atoms that are not the input's " + std::to_string(p.size()) +
                     "; restart with the input that wrote it");
  }
  p.position = c.position;
  p.velocity = c.velocity;
  p.image = c.image;
  system.step = c.step;
  system.time = c.time;
}

void CheckpointWriter::on_step_complete(const System& system) {
  if (system.step % every_ != 0) return;
  write_checkpoint(path_, system, integrator_);
}

}  // namespace deli
