// libFuzzer target: the TOML run input (parse_run_input), as a user writes it.
// Refusing the input with an InputError is the expected outcome; anything else that
// escapes (another exception, a crash, a sanitizer report, a hang, an allocation
// beyond the fuzzer's limit) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "input/run_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // Anchored in inputs/paper/: the seeds' data files (a few atoms each) are found, so
    // the sections after [system] are reached. Reading an input writes nothing.
    deli::parse_run_input(text, DELI_SOURCE_DIR "/inputs/paper/fuzz-input.toml");
  } catch (const deli::InputError&) {
  }
  return 0;
}
