// libFuzzer target: the LAMMPS data file reader (read_lammps_data), with the atom style
// taken from the file as `read_data` in an input does. An InputError is the expected
// refusal; anything else that escapes is a finding.
#include <cstddef>
#include <cstdint>

#include "core/error.hpp"
#include "fuzz/fuzz_file.hpp"
#include "input/lammps_data.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file;
  const std::string path = file.hold(data, size);
  try {
    deli::read_lammps_data(path, deli::LammpsDataOptions{});
  } catch (const deli::InputError&) {
  }
  return 0;
}
