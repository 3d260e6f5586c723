#include "h5md/h5md_info.hpp"

#include <hdf5.h>

#include <sstream>
#include <vector>

#include "core/error.hpp"

namespace deli {

namespace {

std::vector<hsize_t> shape_of(hid_t file, const std::string& path) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  H5Dclose(set);
  return dims;
}

double double_at(hid_t file, const std::string& path, hsize_t index) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(set);
  H5Sselect_elements(space, H5S_SELECT_SET, 1, &index);
  const hsize_t one = 1;
  const hid_t memory = H5Screate_simple(1, &one, nullptr);
  double value = 0;
  H5Dread(set, H5T_NATIVE_DOUBLE, memory, space, H5P_DEFAULT, &value);
  H5Sclose(memory);
  H5Sclose(space);
  H5Dclose(set);
  return value;
}

std::vector<std::string> children(hid_t file, const std::string& path) {
  std::vector<std::string> names;
  if (H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0) return names;
  const hid_t g = H5Gopen2(file, path.c_str(), H5P_DEFAULT);
  H5G_info_t info;
  H5Gget_info(g, &info);
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    char name[256];
    H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT);
    names.emplace_back(name);
  }
  H5Gclose(g);
  return names;
}

std::string string_attribute(hid_t file, const std::string& object, const char* name) {
  if (H5Aexists_by_name(file, object.c_str(), name, H5P_DEFAULT) <= 0) return "?";
  const hid_t attr = H5Aopen_by_name(file, object.c_str(), name, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t type = H5Aget_type(attr);
  std::string value(H5Tget_size(type), '\0');
  H5Aread(attr, type, value.data());
  H5Tclose(type);
  H5Aclose(attr);
  return value.c_str();
}

}  // namespace

std::string describe_h5md(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    throw InputError(path + ": not an HDF5 file (deli info reads H5MD trajectories)");
  }
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw InputError(path + ": cannot be opened (truncated or damaged?)");
  std::ostringstream out;
  if (H5Lexists(file, "/neighbor_build_positions", H5P_DEFAULT) > 0) {
    const std::vector<hsize_t> position = shape_of(file, "/position");
    std::int64_t step = 0;
    const hid_t set = H5Dopen2(file, "/step", H5P_DEFAULT);
    H5Dread(set, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &step);
    H5Dclose(set);
    out << path << ": deli checkpoint, " << (position.empty() ? 0 : position[0])
        << " atoms at step " << step << ", time " << double_at(file, "/time", 0)
        << "\n  fields: position velocity image neighbor_build_positions\n";
    H5Fclose(file);
    return out.str();
  }
  if (H5Lexists(file, "/h5md", H5P_DEFAULT) <= 0 ||
      H5Lexists(file, "/particles", H5P_DEFAULT) <= 0) {
    H5Fclose(file);
    throw InputError(path + ": an HDF5 file without /h5md and /particles: not H5MD");
  }
  out << path << ": H5MD, written by " << string_attribute(file, "/h5md/creator", "name") << ' '
      << string_attribute(file, "/h5md/creator", "version") << '\n';
  for (const std::string& group : children(file, "/particles")) {
    const std::string base = "/particles/" + group;
    const std::vector<hsize_t> position = shape_of(file, base + "/position/value");
    const hsize_t frames = position.empty() ? 0 : position[0];
    out << "particles/" << group << ": " << (position.size() > 1 ? position[1] : 0) << " atoms, "
        << frames << " frames";
    if (frames > 0) {
      out << ", time " << double_at(file, base + "/position/time", 0) << " to "
          << double_at(file, base + "/position/time", frames - 1);
    }
    out << "\n  fields:";
    for (const std::string& field : children(file, base)) out << ' ' << field;
    out << '\n';
  }
  const std::vector<std::string> observables = children(file, "/observables");
  out << "observables (" << observables.size() << "):";
  for (const std::string& o : observables) out << ' ' << o;
  out << '\n';
  const std::vector<hsize_t> temperatures = shape_of(file, "/observables/temperature/value");
  if (!temperatures.empty() && temperatures[0] > 0 &&
      H5Lexists(file, "/observables/degrees_of_freedom", H5P_DEFAULT) > 0) {
    double mean = 0;
    for (hsize_t k = 0; k < temperatures[0]; ++k)
      mean += double_at(file, "/observables/temperature/value", k);
    out << "temperature: mean " << mean / static_cast<double>(temperatures[0]) << " over "
        << temperatures[0] << " frames, "
        << double_at(file, "/observables/degrees_of_freedom/value", 0) << " degrees of freedom\n";
  }
  const std::vector<hsize_t> bonds = shape_of(file, "/connectivity/bonds");
  out << "bonds: " << (bonds.empty() ? 0 : bonds[0]) << '\n';
  H5Fclose(file);
  return out.str();
}

}  // namespace deli
