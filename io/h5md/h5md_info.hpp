#pragma once

#include <string>

namespace deli {

// A summary of an H5MD file deli wrote (or any H5MD 1.1 file): creator, atoms, frames,
// time span, per-particle fields, observables, bonds; or of a deli checkpoint. Throws InputError
// naming the file when it is not HDF5 or not H5MD.
std::string describe_h5md(const std::string& path);

}  // namespace deli
