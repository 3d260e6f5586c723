#include "h5md/h5md_writer.hpp"

#include <algorithm>
#include <array>

#include "core/error.hpp"
#include "system/particle_order.hpp"

namespace deli {

namespace {

// Fails with the file's name: HDF5 reports through return codes, never exceptions.
void check(herr_t status, const std::string& file, const char* what) {
  if (status < 0) {
    throw SimulationError(file + ": HDF5 failed to " + std::string(what) +
                          " (disk full or not writable?); the frames written before are kept");
  }
}
H5Handle checked(H5Handle handle, const std::string& file, const char* what) {
  if (!handle.valid()) check(-1, file, what);
  return handle;
}

void write_attribute(hid_t object, const char* name, hid_t type, hid_t space, const void* data,
                     const std::string& file) {
  H5Handle attr =
      checked(h5_attribute(H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT)), file,
              "create an attribute");
  check(H5Awrite(attr, type, data), file, "write an attribute");
  check(attr.close(), file, "close an attribute");
}

void string_attribute(hid_t object, const char* name, const std::string& value,
                      const std::string& file) {
  H5Handle type = h5_type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type, value.size() + 1);
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  H5Handle space = h5_space(H5Screate(H5S_SCALAR));
  write_attribute(object, name, type, space, value.c_str(), file);
}

void strings_attribute(hid_t object, const char* name, const std::vector<std::string>& values,
                       const std::string& file) {
  std::size_t width = 1;
  for (const std::string& v : values) width = std::max(width, v.size() + 1);
  std::vector<char> buffer(width * values.size(), '\0');
  for (std::size_t k = 0; k < values.size(); ++k)
    values[k].copy(&buffer[k * width], values[k].size());
  H5Handle type = h5_type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type, width);
  const hsize_t n = values.size();
  H5Handle space = h5_space(H5Screate_simple(1, &n, nullptr));
  write_attribute(object, name, type, space, buffer.data(), file);
}

void int_attribute(hid_t object, const char* name, const std::vector<int>& values,
                   const std::string& file) {
  const hsize_t n = values.size();
  H5Handle space =
      h5_space(values.size() == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr));
  write_attribute(object, name, H5T_NATIVE_INT, space, values.data(), file);
}

template <class T>
void fixed_dataset(hid_t parent, const char* name, hid_t type, const std::vector<hsize_t>& shape,
                   const std::vector<T>& data, const std::string& file) {
  H5Handle space =
      h5_space(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr));
  H5Handle set = checked(
      h5_dataset(H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)),
      file, "create a dataset");
  if (!data.empty()) {
    check(H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), file, "write a dataset");
  }
  check(set.close(), file, "close a dataset");
}

// The length of a dataset's first (time) dimension.
hsize_t first_extent(hid_t set) {
  H5Handle space = h5_space(H5Dget_space(set));
  std::vector<hsize_t> dims(
      static_cast<std::size_t>(std::max(H5Sget_simple_extent_ndims(space), 1)));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  return dims[0];
}

H5Handle group(hid_t parent, const char* name, const std::string& file) {
  return checked(h5_group(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)), file,
                 "create a group");
}

}  // namespace

H5mdWriter::H5mdWriter(const TrajectorySpec& spec, const System& system,
                       const std::string& input_text, const std::string& author,
                       const std::vector<std::pair<std::int32_t, std::int32_t>>& rods,
                       bool hard_spheres, TrajectoryContinuation continuation)
    : spec_(spec), atoms_(system.particles.size()) {
  prepare_hdf5();
  // On an error the handles close what was opened (the destructors).
  if (continuation.step >= 0 && H5Fis_hdf5(spec.file.c_str()) > 0) {
    reopen(system, continuation.step);
    return;
  }
  create(system, input_text, author, rods, hard_spheres);
}

void H5mdWriter::create(const System& system, const std::string& input_text,
                        const std::string& author,
                        const std::vector<std::pair<std::int32_t, std::int32_t>>& rods,
                        bool hard_spheres) {
  const std::string& f = spec_.file;
  file_ = h5_file(H5Fcreate(f.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  if (!file_.valid()) {
    throw InputError(f +
                     ": cannot create the trajectory file; check that the "
                     "directory exists and is writable");
  }
  {
    H5Handle h5md = group(file_, "h5md", f);
    int_attribute(h5md, "version", {1, 1}, f);
    H5Handle author_group = group(h5md, "author", f);
    string_attribute(author_group, "name", author, f);
    H5Handle creator = group(h5md, "creator", f);
    string_attribute(creator, "name", "deli", f);
    string_attribute(creator, "version", DELI_VERSION, f);
  }

  const Particles& p = system.particles;
  {
    H5Handle particles = group(file_, "particles", f);
    H5Handle all = group(particles, "all", f);
    const hsize_t n = p.size();
    // Rows in the input's order, whatever order the run has put the particles in.
    const Particles listed = in_input_order(system).particles;
    std::vector<int> species(listed.type.begin(), listed.type.end());
    for (int& t : species) t += 1;  // LAMMPS type numbers
    fixed_dataset(all, "species", H5T_NATIVE_INT, {n}, species, f);
    fixed_dataset(all, "mass", H5T_NATIVE_DOUBLE, {n}, listed.mass, f);
    fixed_dataset(all, "id", H5T_NATIVE_INT64, {n}, listed.id, f);
    // Hard-sphere diameters (not an H5MD 1.1 element: the specification allows others; the
    // name is GSD's and HOOMD's). Point particles have none.
    if (hard_spheres) {
      std::vector<double> diameter(listed.radius.size());
      for (std::size_t i = 0; i < listed.size(); ++i) diameter[i] = 2 * listed.radius[i];
      fixed_dataset(all, "diameter", H5T_NATIVE_DOUBLE, {n}, diameter, f);
    }
    H5Handle box = group(all, "box", f);
    int_attribute(box, "dimension", {3}, f);
    std::vector<std::string> boundary;
    for (int a = 0; a < 3; ++a) boundary.push_back(system.box.periodic(a) ? "periodic" : "none");
    strings_attribute(box, "boundary", boundary, f);
    // Every series is sampled at the position's frames: their step and time are hard links
    // to the position's (H5MD 1.1 requires it of box/edges and image, allows it elsewhere).
    position_ = make_series(all, "position", H5T_NATIVE_DOUBLE, {n, 3});
    edges_ = make_series(box, "edges", H5T_NATIVE_DOUBLE, {3, 3}, &position_);
    if (spec_.velocities) {
      velocity_ = make_series(all, "velocity", H5T_NATIVE_DOUBLE, {n, 3}, &position_);
    }
    if (spec_.forces) force_ = make_series(all, "force", H5T_NATIVE_DOUBLE, {n, 3}, &position_);
    if (spec_.images) image_ = make_series(all, "image", H5T_NATIVE_INT, {n, 3}, &position_);
  }

  observables_group_ = group(file_, "observables", f);

  if (!system.topology.bonds.empty() || !rods.empty()) {
    H5Handle connectivity = group(file_, "connectivity", f);
    // Pairs of particle ids: H5MD 1.1 reads the tuples of a list whose particles_group has
    // an `id` element as values of that `id` (as indices only where it has none).
    auto pair_list = [&](const char* name, const std::vector<std::int64_t>& pairs) {
      if (pairs.empty()) return;
      fixed_dataset(connectivity, name, H5T_NATIVE_INT64, {pairs.size() / 2, 2}, pairs, f);
      H5Handle set =
          checked(h5_dataset(H5Dopen2(connectivity, name, H5P_DEFAULT)), f, "open a dataset");
      hobj_ref_t reference;
      check(H5Rcreate(&reference, file_, "/particles/all", H5R_OBJECT, -1), f,
            "create a reference");
      H5Handle space = h5_space(H5Screate(H5S_SCALAR));
      write_attribute(set, "particles_group", H5T_STD_REF_OBJ, space, &reference, f);
      check(set.close(), f, "close a dataset");
    };
    std::vector<std::int64_t> bonds, rod_pairs;
    for (const Bond& b : system.topology.bonds)
      bonds.push_back(p.id[b.i]), bonds.push_back(p.id[b.j]);
    for (const auto& [i, j] : rods) rod_pairs.push_back(p.id[i]), rod_pairs.push_back(p.id[j]);
    pair_list("bonds", bonds);
    pair_list("rods", rod_pairs);
  }

  {
    H5Handle parameters = group(file_, "parameters", f);
    string_attribute(parameters, "input", input_text, f);
  }
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), f, "flush the file");
}

H5mdWriter::Series H5mdWriter::continue_series(hid_t parent, const std::string& name,
                                               std::int64_t step) {
  Series s;
  s.group = h5_group(H5Gopen2(parent, name.c_str(), H5P_DEFAULT));
  if (s.group.valid()) {
    s.step = h5_dataset(H5Dopen2(s.group, "step", H5P_DEFAULT));
    s.time = h5_dataset(H5Dopen2(s.group, "time", H5P_DEFAULT));
    s.value = h5_dataset(H5Dopen2(s.group, "value", H5P_DEFAULT));
  }
  if (!s.group.valid() || !s.step.valid() || !s.time.valid() || !s.value.valid()) {
    throw InputError(spec_.file + ": cannot continue this trajectory: it has no readable " + name +
                     " series; move the file aside to start a new one");
  }
  hsize_t frames = 0;
  {
    H5Handle space = h5_space(H5Dget_space(s.step));
    H5Sget_simple_extent_dims(space, &frames, nullptr);
  }
  std::vector<std::int64_t> steps(frames);
  if (frames > 0) {
    check(H5Dread(s.step, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, steps.data()),
          spec_.file, "read the frame steps");
  }
  const auto keep =
      static_cast<hsize_t>(std::upper_bound(steps.begin(), steps.end(), step) - steps.begin());
  for (hid_t set : {s.step.get(), s.time.get(), s.value.get()}) {
    std::vector<hsize_t> dims;
    {
      H5Handle space = h5_space(H5Dget_space(set));
      dims.resize(static_cast<std::size_t>(std::max(H5Sget_simple_extent_ndims(space), 1)));
      H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    }
    dims[0] = keep;
    check(H5Dset_extent(set, dims.data()), spec_.file, "cut the trajectory back to the checkpoint");
  }
  return s;
}

void H5mdWriter::reopen(const System& system, std::int64_t step) {
  file_ = h5_file(H5Fopen(spec_.file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
  if (!file_.valid()) {
    throw InputError(spec_.file +
                     ": cannot open the trajectory to continue it; check that it is writable");
  }
  H5Handle all = h5_group(H5Gopen2(file_, "/particles/all", H5P_DEFAULT));
  if (!all.valid()) {
    throw InputError(spec_.file +
                     ": not a deli H5MD trajectory (no /particles/all); move it aside or name "
                     "another trajectory file");
  }
  auto has = [&](const char* name) { return H5Lexists(all, name, H5P_DEFAULT) > 0; };
  for (const auto& [name, wanted] :
       {std::pair{"velocity", spec_.velocities}, std::pair{"force", spec_.forces},
        std::pair{"image", spec_.images}}) {
    if (has(name) != wanted) {
      throw InputError(spec_.file + ": the trajectory " + (wanted ? "lacks" : "has") + " " + name +
                       " frames, the input " + (wanted ? "asks for" : "does not ask for") +
                       " them; keep [output] trajectory as it was to continue the file");
    }
  }
  position_ = continue_series(all, "position", step);
  hsize_t dims[3] = {0, 0, 0};
  {
    H5Handle space = h5_space(H5Dget_space(position_.value));
    if (H5Sget_simple_extent_ndims(space) == 3) H5Sget_simple_extent_dims(space, dims, nullptr);
  }
  if (dims[1] != system.particles.size()) {
    throw InputError(spec_.file + ": the trajectory holds " + std::to_string(dims[1]) +
                     " atoms, the run " + std::to_string(system.particles.size()) +
                     "; it belongs to another system");
  }
  if (spec_.velocities) velocity_ = continue_series(all, "velocity", step);
  if (spec_.forces) force_ = continue_series(all, "force", step);
  if (spec_.images) image_ = continue_series(all, "image", step);
  {
    H5Handle box = h5_group(H5Gopen2(all, "box", H5P_DEFAULT));
    if (!box.valid()) {
      throw InputError(spec_.file +
                       ": cannot continue this trajectory: it has no box; move the "
                       "file aside to start a new one");
    }
    edges_ = continue_series(box, "edges", step);
  }
  observables_group_ = h5_group(H5Gopen2(file_, "observables", H5P_DEFAULT));
  if (!observables_group_.valid()) {
    throw InputError(spec_.file +
                     ": cannot continue this trajectory: it has no /observables; move the file "
                     "aside to start a new one");
  }
  hsize_t count = 0;
  H5Gget_num_objs(observables_group_, &count);
  for (hsize_t k = 0; k < count; ++k) {
    char name[256] = {};
    H5Gget_objname_by_idx(observables_group_, k, name, sizeof name);
    observables_.emplace(name, continue_series(observables_group_, name, step));
  }
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), spec_.file, "flush the file");
}

// An error path (a frame that failed, an exception elsewhere): close without reporting.
H5mdWriter::~H5mdWriter() = default;

H5mdWriter::Series H5mdWriter::make_series(hid_t parent, const std::string& name, hid_t type,
                                           const std::vector<hsize_t>& frame_shape,
                                           const Series* clock) {
  Series s;
  s.group = group(parent, name.c_str(), spec_.file);
  const hsize_t unlimited = H5S_UNLIMITED, one = 1;
  auto series_dataset = [&](const char* dname, hid_t dtype, const std::vector<hsize_t>& shape) {
    std::vector<hsize_t> dims{0}, max{unlimited}, chunk{one};
    for (hsize_t d : shape) dims.push_back(d), max.push_back(d), chunk.push_back(d);
    H5Handle space =
        h5_space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max.data()));
    H5Handle properties = h5_properties(H5Pcreate(H5P_DATASET_CREATE));
    // One frame per chunk: appending never rewrites earlier chunks.
    if (shape.empty()) chunk[0] = 1024;
    H5Pset_chunk(properties, static_cast<int>(chunk.size()), chunk.data());
    if (spec_.compression > 0 && !shape.empty()) {
      H5Pset_shuffle(properties);
      H5Pset_deflate(properties, static_cast<unsigned>(spec_.compression));
    }
    return checked(
        h5_dataset(H5Dcreate2(s.group, dname, dtype, space, H5P_DEFAULT, properties, H5P_DEFAULT)),
        spec_.file, "create a dataset");
  };
  if (clock != nullptr) {
    for (const char* link : {"step", "time"}) {
      check(H5Lcreate_hard(clock->group, link, s.group, link, H5P_DEFAULT, H5P_DEFAULT), spec_.file,
            "link a series to the position's step and time");
    }
    s.step =
        checked(h5_dataset(H5Dopen2(s.group, "step", H5P_DEFAULT)), spec_.file, "open a dataset");
    s.time =
        checked(h5_dataset(H5Dopen2(s.group, "time", H5P_DEFAULT)), spec_.file, "open a dataset");
  } else {
    s.step = series_dataset("step", H5T_NATIVE_INT64, {});
    s.time = series_dataset("time", H5T_NATIVE_DOUBLE, {});
  }
  s.value = series_dataset("value", type, frame_shape);
  return s;
}

void H5mdWriter::append(Series& s, std::int64_t step, double time, const void* data,
                        hid_t memory_type, const std::vector<hsize_t>& frame_shape) {
  auto grow_and_write = [&](hid_t set, hid_t type, const void* values,
                            const std::vector<hsize_t>& shape) {
    std::vector<hsize_t> dims;
    {
      H5Handle space = h5_space(H5Dget_space(set));
      dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
      H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    }
    const hsize_t at = dims[0];
    dims[0] = at + 1;
    check(H5Dset_extent(set, dims.data()), spec_.file, "extend a dataset");
    H5Handle space = h5_space(H5Dget_space(set));
    std::vector<hsize_t> start(dims.size(), 0), count{1};
    start[0] = at;
    for (hsize_t d : shape) count.push_back(d);
    check(H5Sselect_hyperslab(space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
          spec_.file, "select a frame");
    H5Handle memory =
        h5_space(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr));
    check(H5Dwrite(set, type, memory, space, H5P_DEFAULT, values), spec_.file, "write a frame");
  };
  // A step and time shared with other series (hard links) are extended by the first of
  // them to write the frame: once, whichever series comes first.
  const hsize_t frames = first_extent(s.value);
  const hsize_t stamped = first_extent(s.step);
  if (stamped == frames) {
    grow_and_write(s.step, H5T_NATIVE_INT64, &step, {});
    grow_and_write(s.time, H5T_NATIVE_DOUBLE, &time, {});
  } else if (stamped != frames + 1) {
    check(-1, spec_.file, "keep a series' step and value the same length");
  }
  grow_and_write(s.value, memory_type, data, frame_shape);
}

void H5mdWriter::on_frame(const System& system, const ThermoSample& sample,
                          const std::vector<Vec3>& forces) {
  // Rows in the input's order (the `id` element's), whatever order the run has reached.
  const Particles& p = system.particles;
  const hsize_t n = atoms_;
  auto listed = [&](const std::vector<Vec3>& values) {
    return in_input_order(values, p, listed_vectors_).data();
  };
  append(position_, system.step, system.time, listed(p.position), H5T_NATIVE_DOUBLE, {n, 3});
  if (spec_.velocities) {
    append(velocity_, system.step, system.time, listed(p.velocity), H5T_NATIVE_DOUBLE, {n, 3});
  }
  if (spec_.forces) {
    append(force_, system.step, system.time, listed(forces), H5T_NATIVE_DOUBLE, {n, 3});
  }
  if (spec_.images) {
    append(image_, system.step, system.time, in_input_order(p.image, p, listed_images_).data(),
           H5T_NATIVE_INT, {n, 3});
  }
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
  if (sample.conserved) {
    values.emplace_back("bath_energy", *sample.bath_energy);
    values.emplace_back("conserved_energy", *sample.conserved);
  }
  values.emplace_back("degrees_of_freedom", sample.degrees_of_freedom);
  if (sample.angular_momentum) {
    values.emplace_back("angular_momentum_x", sample.angular_momentum->x);
    values.emplace_back("angular_momentum_y", sample.angular_momentum->y);
    values.emplace_back("angular_momentum_z", sample.angular_momentum->z);
  }
  for (const auto& [name, value] : sample.integrator) values.emplace_back(name, value);
  for (const auto& [name, value] : values) {
    auto it = observables_.find(name);
    if (it == observables_.end()) {
      // An observable from the file's first frame on shares the position's step and time;
      // one that appears later has its own.
      const bool from_first_frame = first_extent(position_.step) == 1;
      it = observables_
               .emplace(name, make_series(observables_group_, name, H5T_NATIVE_DOUBLE, {},
                                          from_first_frame ? &position_ : nullptr))
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
  if (!file_.valid()) return;
  herr_t status = 0;
  auto close_series = [&status](Series& s) {
    for (H5Handle* h : {&s.step, &s.time, &s.value, &s.group})
      status = std::min(status, h->close());
  };
  close_series(position_);
  close_series(velocity_);
  close_series(force_);
  close_series(image_);
  close_series(edges_);
  for (auto& [name, s] : observables_) close_series(s);
  status = std::min(status, observables_group_.close());
  status = std::min(status, file_.close());
  check(status, spec_.file, "close the trajectory");
}

}  // namespace deli
