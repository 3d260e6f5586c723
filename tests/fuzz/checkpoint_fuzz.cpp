// libFuzzer target: the checkpoint reader (read_checkpoint) on the bytes of a damaged
// HDF5 file. An InputError (missing, damaged, inconsistent) is the expected refusal;
// anything else that escapes is a finding. HDF5 itself is an uninstrumented Debian
// library: a crash inside it shows as a SEGV with libhdf5 frames, to report upstream.
#include <cstddef>
#include <cstdint>

#include "core/error.hpp"
#include "fuzz/fuzz_file.hpp"
#include "h5md/checkpoint.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file(/*on_disk=*/true);
  const std::string path = file.hold(data, size);
  try {
    deli::read_checkpoint(path);
  } catch (const deli::InputError&) {
  }
  return 0;
}
