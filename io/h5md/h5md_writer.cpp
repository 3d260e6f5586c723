#include "h5md/h5md_writer.hpp"

#include <array>

#include "core/error.hpp"

namespace deli {

namespace {

// Fails with the file's name: HDF5 reports through return codes, never exceptions.
void check(herr_t status, const std::string& file, const char* what) {
  if (status < 0) {
    throw SimulationError(file + ": HDF5 failed to " + std::string(what) +
                          " (disk full or not writable?)");
  }
}
hid_t checked(hid_t id, const std::string& file, const char* what) {
  if (id < 0) check(-1, file, what);
  return id;
}

void string_attribute(hid_t object, const char* name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size() + 1);
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attr, type, value.c_str());
  H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
}

void strings_attribute(hid_t object, const char* name, const std::vector<std::string>& values) {
  std::size_t width = 1;
  for (const std::string& v : values) width = std::max(width, v.size() + 1);
  std::vector<char> buffer(width * values.size(), '\0');
  for (std::size_t k = 0; k < values.size(); ++k)
    values[k].copy(&buffer[k * width], values[k].size());
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, width);
  const hsize_t n = values.size();
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t attr = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attr, type, buffer.data());
  H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
}

void int_attribute(hid_t object, const char* name, const std::vector<int>& values) {
  const hsize_t n = values.size();
  const hid_t space = values.size() == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr);
  const hid_t attr = H5Acreate2(object, name, H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attr, H5T_NATIVE_INT, values.data());
  H5Aclose(attr);
  H5Sclose(space);
}

template <class T>
void fixed_dataset(hid_t parent, const char* name, hid_t type, const std::vector<hsize_t>& shape,
                   const std::vector<T>& data) {
  const hid_t space = H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr);
  const hid_t set = H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (!data.empty()) H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data());
  H5Dclose(set);
  H5Sclose(space);
}

hid_t group(hid_t parent, const char* name) {
  return H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
}

}  // namespace

H5mdWriter::H5mdWriter(const TrajectorySpec& spec, const System& system,
                       const std::string& input_text, const std::string& author)
    : spec_(spec), atoms_(system.particles.size()) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors come back as codes, reported by us
  file_ = H5Fcreate(spec.file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) {
    throw InputError(spec.file +
                     ": cannot create the trajectory file; check that the "
                     "directory exists and is writable");
  }
  const hid_t h5md = group(file_, "h5md");
  int_attribute(h5md, "version", {1, 1});
  const hid_t author_group = group(h5md, "author");
  string_attribute(author_group, "name", author);
  H5Gclose(author_group);
  const hid_t creator = group(h5md, "creator");
  string_attribute(creator, "name", "deli");
  string_attribute(creator, "version", DELI_VERSION);
  H5Gclose(creator);
  H5Gclose(h5md);

  const Particles& p = system.particles;
  const hid_t particles = group(file_, "particles");
  const hid_t all = group(particles, "all");
  const hsize_t n = p.size();
  std::vector<int> species(p.type.begin(), p.type.end());
  for (int& t : species) t += 1;  // LAMMPS type numbers
  fixed_dataset(all, "species", H5T_NATIVE_INT, {n}, species);
  fixed_dataset(all, "mass", H5T_NATIVE_DOUBLE, {n}, p.mass);
  fixed_dataset(all, "id", H5T_NATIVE_INT64, {n}, p.id);
  const hid_t box = group(all, "box");
  int_attribute(box, "dimension", {3});
  std::vector<std::string> boundary;
  for (int a = 0; a < 3; ++a) boundary.push_back(system.box.periodic(a) ? "periodic" : "none");
  strings_attribute(box, "boundary", boundary);
  edges_ = make_series(box, "edges", H5T_NATIVE_DOUBLE, {3, 3});
  H5Gclose(box);
  position_ = make_series(all, "position", H5T_NATIVE_DOUBLE, {n, 3});
  if (spec.velocities) velocity_ = make_series(all, "velocity", H5T_NATIVE_DOUBLE, {n, 3});
  if (spec.images) image_ = make_series(all, "image", H5T_NATIVE_INT, {n, 3});
  H5Gclose(all);
  H5Gclose(particles);

  observables_group_ = group(file_, "observables");

  if (!system.topology.bonds.empty()) {
    const hid_t connectivity = group(file_, "connectivity");
    std::vector<std::int64_t> pairs;
    for (const Bond& b : system.topology.bonds) pairs.push_back(b.i), pairs.push_back(b.j);
    fixed_dataset(connectivity, "bonds", H5T_NATIVE_INT64, {system.topology.bonds.size(), 2},
                  pairs);
    // Indices into /particles/all (0-based), as the H5MD connectivity module specifies.
    const hid_t bonds = H5Dopen2(connectivity, "bonds", H5P_DEFAULT);
    hobj_ref_t reference;
    H5Rcreate(&reference, file_, "/particles/all", H5R_OBJECT, -1);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr =
        H5Acreate2(bonds, "particles_group", H5T_STD_REF_OBJ, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attr, H5T_STD_REF_OBJ, &reference);
    H5Aclose(attr);
    H5Sclose(space);
    H5Dclose(bonds);
    H5Gclose(connectivity);
  }

  const hid_t parameters = group(file_, "parameters");
  string_attribute(parameters, "input", input_text);
  H5Gclose(parameters);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), spec_.file, "flush the file");
}

H5mdWriter::~H5mdWriter() {
  close();
}

H5mdWriter::Series H5mdWriter::make_series(hid_t parent, const std::string& name, hid_t type,
                                           const std::vector<hsize_t>& frame_shape) {
  Series s;
  s.group = checked(group(parent, name.c_str()), spec_.file, "create a group");
  const hsize_t zero = 0, unlimited = H5S_UNLIMITED, one = 1;
  auto series_dataset = [&](const char* dname, hid_t dtype, const std::vector<hsize_t>& shape) {
    std::vector<hsize_t> dims{0}, max{unlimited}, chunk{one};
    for (hsize_t d : shape) dims.push_back(d), max.push_back(d), chunk.push_back(d);
    const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max.data());
    const hid_t properties = H5Pcreate(H5P_DATASET_CREATE);
    // One frame per chunk: appending never rewrites earlier chunks.
    if (shape.empty()) chunk[0] = 1024;
    H5Pset_chunk(properties, static_cast<int>(chunk.size()), chunk.data());
    if (spec_.compression > 0 && !shape.empty()) {
      H5Pset_shuffle(properties);
      H5Pset_deflate(properties, static_cast<unsigned>(spec_.compression));
    }
    const hid_t set =
        H5Dcreate2(s.group, dname, dtype, space, H5P_DEFAULT, properties, H5P_DEFAULT);
    H5Pclose(properties);
    H5Sclose(space);
    return checked(set, spec_.file, "create a dataset");
  };
  (void)zero;
  s.step = series_dataset("step", H5T_NATIVE_INT64, {});
  s.time = series_dataset("time", H5T_NATIVE_DOUBLE, {});
  s.value = series_dataset("value", type, frame_shape);
  return s;
}

void H5mdWriter::append(Series& s, std::int64_t step, double time, const void* data,
                        hid_t memory_type, const std::vector<hsize_t>& frame_shape) {
  auto grow_and_write = [&](hid_t set, hid_t type, const void* values,
                            const std::vector<hsize_t>& shape) {
    hid_t space = H5Dget_space(set);
    std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    H5Sclose(space);
    const hsize_t at = dims[0];
    dims[0] = at + 1;
    check(H5Dset_extent(set, dims.data()), spec_.file, "extend a dataset");
    space = H5Dget_space(set);
    std::vector<hsize_t> start(dims.size(), 0), count{1};
    start[0] = at;
    for (hsize_t d : shape) count.push_back(d);
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
    const hid_t memory = H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr);
    check(H5Dwrite(set, type, memory, space, H5P_DEFAULT, values), spec_.file, "write a frame");
    H5Sclose(memory);
    H5Sclose(space);
  };
  grow_and_write(s.step, H5T_NATIVE_INT64, &step, {});
  grow_and_write(s.time, H5T_NATIVE_DOUBLE, &time, {});
  grow_and_write(s.value, memory_type, data, frame_shape);
}

void H5mdWriter::on_frame(const System& system, const ThermoSample& sample) {
  const Particles& p = system.particles;
  const hsize_t n = atoms_;
  append(position_, system.step, system.time, p.position.data(), H5T_NATIVE_DOUBLE, {n, 3});
  if (spec_.velocities) {
    append(velocity_, system.step, system.time, p.velocity.data(), H5T_NATIVE_DOUBLE, {n, 3});
  }
  if (spec_.images)
    append(image_, system.step, system.time, p.image.data(), H5T_NATIVE_INT, {n, 3});
  const Vec3 l = system.box.length();
  const std::array<double, 9> edges{l.x, 0, 0, 0, l.y, 0, 0, 0, l.z};
  append(edges_, system.step, system.time, edges.data(), H5T_NATIVE_DOUBLE, {3, 3});

  std::vector<std::pair<std::string, double>> values{
      {"kinetic_energy", sample.kinetic}, {"potential_energy", sample.potential},
      {"total_energy", sample.total},     {"temperature", sample.temperature},
      {"pressure", sample.pressure},      {"momentum_x", sample.momentum.x},
      {"momentum_y", sample.momentum.y},  {"momentum_z", sample.momentum.z}};
  for (std::size_t t = 0; t < sample.term_names.size(); ++t) {
    values.emplace_back("energy_" + sample.term_names[t], sample.term_energies[t]);
  }
  if (sample.shadow_energy) values.emplace_back("shadow_energy", *sample.shadow_energy);
  for (const auto& [name, value] : values) {
    auto it = observables_.find(name);
    if (it == observables_.end()) {
      it = observables_.emplace(name, make_series(observables_group_, name, H5T_NATIVE_DOUBLE, {}))
               .first;
    }
    append(it->second, system.step, system.time, &value, H5T_NATIVE_DOUBLE, {});
  }
  ++frames_;
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), spec_.file, "flush the file");
}

void H5mdWriter::on_finish(const System&) {
  close();
}

void H5mdWriter::close() {
  if (file_ < 0) return;
  auto close_series = [](Series& s) {
    for (hid_t* id : {&s.step, &s.time, &s.value}) {
      if (*id >= 0) H5Dclose(*id), *id = -1;
    }
    if (s.group >= 0) H5Gclose(s.group), s.group = -1;
  };
  close_series(position_);
  close_series(velocity_);
  close_series(image_);
  close_series(edges_);
  for (auto& [name, s] : observables_) close_series(s);
  if (observables_group_ >= 0) H5Gclose(observables_group_);
  H5Fclose(file_);
  file_ = -1;
}

}  // namespace deli
