#include "h5md/checkpoint.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"
#include "h5md/fingerprint.hpp"
#include "h5md/h5_handle.hpp"
#include "integrators/integrator.hpp"

namespace deli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kChecksum = "fnv1a64";

void write_failed(const std::string& path, const std::string& what) {
  throw SimulationError(path + ": could not write the checkpoint (" + what +
                        "; disk full or not writable?)");
}

// A dataset and the checksum of its bytes as held in memory, so that any change of the
// stored values (a flipped byte in the data or in the type that converts it) is found.
template <class T>
void write_set(hid_t file, const char* name, hid_t type, const std::vector<hsize_t>& shape,
               const T* data, std::size_t count, const std::string& path) {
  H5Handle space =
      h5_space(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr));
  H5Handle set =
      h5_dataset(H5Dcreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!set.valid()) write_failed(path, std::string("creating '") + name + "'");
  if (count > 0 && H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    write_failed(path, std::string("writing '") + name + "'");
  }
  const std::uint64_t checksum = fnv1a(data, count * sizeof(T));
  H5Handle scalar = h5_space(H5Screate(H5S_SCALAR));
  H5Handle attribute =
      h5_attribute(H5Acreate2(set, kChecksum, H5T_STD_U64LE, scalar, H5P_DEFAULT, H5P_DEFAULT));
  if (!attribute.valid() || H5Awrite(attribute, H5T_NATIVE_UINT64, &checksum) < 0 ||
      attribute.close() < 0) {
    write_failed(path, std::string("writing the checksum of '") + name + "'");
  }
  if (set.close() < 0) write_failed(path, std::string("closing '") + name + "'");
}

[[noreturn]] void damaged(const std::string& path, const std::string& name,
                          const std::string& what) {
  throw InputError(path + ": the checkpoint's '" + name + "' " + what +
                   "; the file is damaged or not a deli checkpoint: restart from an intact one");
}

// Reads a whole dataset of `T`, checking its size (when `count` is given) and checksum.
template <class T>
std::vector<T> read_set(hid_t file, const char* name, hid_t type, std::optional<std::size_t> count,
                        const std::string& path) {
  H5Handle set = h5_dataset(H5Dopen2(file, name, H5P_DEFAULT));
  if (!set.valid()) damaged(path, name, "is missing");
  hssize_t points = -1;
  {
    H5Handle space = h5_space(H5Dget_space(set));
    if (space.valid()) points = H5Sget_simple_extent_npoints(space);
  }
  if (points < 0 || (count && static_cast<std::size_t>(points) != *count)) {
    damaged(path, name, "has the wrong size");
  }
  // A damaged shape can claim any number of values: believe only one that the bytes stored
  // hold (before allocating for it).
  hsize_t element = 0;
  {
    H5Handle stored_type = h5_type(H5Dget_type(set));
    if (stored_type.valid()) element = H5Tget_size(stored_type);
  }
  if (element != sizeof(T) ||
      H5Dget_storage_size(set) != static_cast<hsize_t>(points) * sizeof(T)) {
    damaged(path, name, "has a size that does not match its stored bytes");
  }
  std::vector<T> values(static_cast<std::size_t>(points));
  if (points > 0 && H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
    damaged(path, name, "cannot be read");
  }
  std::uint64_t stored = 0;
  {
    H5Handle attribute = h5_attribute(H5Aopen(set, kChecksum, H5P_DEFAULT));
    if (!attribute.valid() || H5Aread(attribute, H5T_NATIVE_UINT64, &stored) < 0) {
      damaged(path, name, "has no checksum");
    }
  }
  if (stored != fnv1a(values.data(), values.size() * sizeof(T))) {
    damaged(path, name, "does not match its checksum");
  }
  return values;
}

template <class T>
T read_one(hid_t file, const char* name, hid_t type, const std::string& path) {
  return read_set<T>(file, name, type, 1, path)[0];
}

std::vector<Vec3> read_vectors(hid_t file, const char* name, std::size_t n,
                               const std::string& path) {
  const std::vector<double> flat = read_set<double>(file, name, H5T_NATIVE_DOUBLE, 3 * n, path);
  std::vector<Vec3> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(v[i].x) || !std::isfinite(v[i].y) || !std::isfinite(v[i].z)) {
      damaged(path, name, "holds a value that is not finite (entry " + std::to_string(i + 1) + ")");
    }
  }
  return v;
}

// Only a regular file (or nothing) is replaced: a symlink or a device named as the
// checkpoint would otherwise be replaced by the rename (as root, /dev/full was).
void check_replaceable(const std::string& path) {
  std::error_code error;
  const fs::file_status status = fs::symlink_status(path, error);
  if (error || status.type() == fs::file_type::not_found) return;
  if (status.type() != fs::file_type::regular) {
    throw SimulationError(path +
                          ": will not write a checkpoint over something that is not a regular "
                          "file (a symlink, a device or a directory); name another file");
  }
}

void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  const bool ok = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  if (!ok) write_failed(path, "fsync failed");
}

void sync_directory_of(const std::string& path) {
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);  // best effort: some file systems refuse fsync on directories
    ::close(fd);
  }
}

bool same_bits(const void* a, const void* b, std::size_t bytes) {
  return bytes == 0 || std::memcmp(a, b, bytes) == 0;
}

void write_file(const std::string& aside, const System& system,
                const std::vector<Vec3>& build_positions,
                const std::vector<double>& integrator_state, std::uint64_t fingerprint) {
  H5Handle file = h5_file(H5Fcreate(aside.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  if (!file.valid()) {
    throw SimulationError(aside +
                          ": cannot create the checkpoint file; check that the "
                          "directory exists and is writable");
  }
  const Particles& p = system.particles;
  const hsize_t n = p.size();
  const std::int64_t step = system.step;
  write_set(file, "step", H5T_NATIVE_INT64, {1}, &step, 1, aside);
  write_set(file, "time", H5T_NATIVE_DOUBLE, {1}, &system.time, 1, aside);
  write_set(file, "fingerprint", H5T_NATIVE_UINT64, {1}, &fingerprint, 1, aside);
  write_set(file, "id", H5T_NATIVE_INT64, {n}, p.id.data(), n, aside);
  write_set(file, "position", H5T_NATIVE_DOUBLE, {n, 3}, &p.position.data()->x, 3 * n, aside);
  write_set(file, "velocity", H5T_NATIVE_DOUBLE, {n, 3}, &p.velocity.data()->x, 3 * n, aside);
  write_set(file, "image", H5T_NATIVE_INT, {n, 3}, p.image.data()->data(), 3 * n, aside);
  write_set(file, "neighbor_build_positions", H5T_NATIVE_DOUBLE, {build_positions.size(), 3},
            build_positions.empty() ? nullptr : &build_positions.data()->x,
            3 * build_positions.size(), aside);
  write_set(file, "integrator_state", H5T_NATIVE_DOUBLE, {integrator_state.size()},
            integrator_state.data(), integrator_state.size(), aside);
  if (file.close() < 0) write_failed(aside, "closing the file");
}

}  // namespace

void write_checkpoint(const std::string& path, const System& system, const Integrator& integrator,
                      std::uint64_t fingerprint) {
  write_checkpoint(path, system, integrator.forces().neighbors().positions_at_build(),
                   integrator.saved_state(), fingerprint);
}

void write_checkpoint(const std::string& path, const System& system,
                      const std::vector<Vec3>& build_positions,
                      const std::vector<double>& integrator_state, std::uint64_t fingerprint) {
  prepare_hdf5();
  const std::string aside = path + ".partial";
  check_replaceable(path);
  check_replaceable(aside);
  try {
    write_file(aside, system, build_positions, integrator_state, fingerprint);
    sync_file(aside);
    // HDF5 has reported success on a full disk and left zeros behind: read it back.
    Checkpoint back;
    try {
      back = read_checkpoint(aside);
    } catch (const InputError& e) {
      throw SimulationError(std::string(e.what()) + " (read back after writing it)");
    }
    const Particles& p = system.particles;
    const bool same =
        back.step == system.step && same_bits(&back.time, &system.time, sizeof(double)) &&
        back.fingerprint == fingerprint && back.id == p.id &&
        same_bits(back.position.data(), p.position.data(), p.size() * sizeof(Vec3)) &&
        same_bits(back.velocity.data(), p.velocity.data(), p.size() * sizeof(Vec3)) &&
        back.image == p.image && back.build_positions.size() == build_positions.size() &&
        same_bits(back.build_positions.data(), build_positions.data(),
                  build_positions.size() * sizeof(Vec3)) &&
        back.integrator_state.size() == integrator_state.size() &&
        same_bits(back.integrator_state.data(), integrator_state.data(),
                  integrator_state.size() * sizeof(double));
    if (!same) write_failed(aside, "it reads back different from what was written");
    if (std::rename(aside.c_str(), path.c_str()) != 0) {
      write_failed(path, std::string("renaming ") + aside + ": " + std::strerror(errno));
    }
  } catch (const SimulationError& e) {
    std::remove(aside.c_str());  // frees the space; the previous checkpoint stays
    throw SimulationError(std::string(e.what()) + "; the previous checkpoint " + path +
                          " (if any) is kept");
  }
  sync_directory_of(path);
}

Checkpoint read_checkpoint(const std::string& path) {
  prepare_hdf5();
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    throw InputError(path + ": not a deli checkpoint (missing, truncated or not HDF5)");
  }
  H5Handle file = h5_file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!file.valid()) throw InputError(path + ": the checkpoint cannot be opened (damaged?)");
  Checkpoint c;
  c.step = read_one<std::int64_t>(file, "step", H5T_NATIVE_INT64, path);
  if (c.step < 0) damaged(path, "step", "is negative (" + std::to_string(c.step) + ")");
  c.time = read_one<double>(file, "time", H5T_NATIVE_DOUBLE, path);
  if (!std::isfinite(c.time) || c.time < 0) {
    damaged(path, "time", "is not a finite non-negative time");
  }
  c.fingerprint = read_one<std::uint64_t>(file, "fingerprint", H5T_NATIVE_UINT64, path);
  c.id = read_set<std::int64_t>(file, "id", H5T_NATIVE_INT64, std::nullopt, path);
  const std::size_t n = c.id.size();
  c.position = read_vectors(file, "position", n, path);
  c.velocity = read_vectors(file, "velocity", n, path);
  const std::vector<int> image = read_set<int>(file, "image", H5T_NATIVE_INT, 3 * n, path);
  c.image.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    c.image[i] = {image[3 * i], image[3 * i + 1], image[3 * i + 2]};
  c.build_positions = read_vectors(file, "neighbor_build_positions", n, path);
  c.integrator_state =
      read_set<double>(file, "integrator_state", H5T_NATIVE_DOUBLE, std::nullopt, path);
  return c;
}

void apply_checkpoint(const Checkpoint& c, System& system, const std::string& path,
                      std::optional<std::uint64_t> fingerprint) {
  Particles& p = system.particles;
  if (c.id != p.id) {
    throw InputError(path + ": the checkpoint holds " + std::to_string(c.id.size()) +
                     " atoms that are not the input's " + std::to_string(p.size()) +
                     "; restart with the input that wrote it");
  }
  if (fingerprint && *fingerprint != c.fingerprint) {
    throw InputError(path +
                     ": the checkpoint belongs to another system: the atom types, masses, "
                     "bonds, box, [forcefield] or [constraints] differ from the input's; restart "
                     "with the input that wrote it");
  }
  p.position = c.position;
  p.velocity = c.velocity;
  p.image = c.image;
  system.step = c.step;
  system.time = c.time;
}

void CheckpointWriter::on_step_complete(const System& system) {
  if (system.step % every_ != 0) return;
  write_checkpoint(path_, system, integrator_, fingerprint_);
}

}  // namespace deli
