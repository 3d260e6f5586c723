#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "system/system.hpp"

namespace deli {

// FNV-1a, 64 bits: checkpoints carry it for every dataset (a flipped byte is found) and
// for the system they belong to.
class Fnv1a {
 public:
  void add(const void* data, std::size_t bytes);
  template <class T>
  void add_value(const T& value) {
    add(&value, sizeof value);
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

std::uint64_t fnv1a(const void* data, std::size_t bytes);

// What a checkpoint must match to be restarted by a run: atom ids, types, masses and
// radii, bonds and angles, the box and its periodicity, and `model` (the force field and
// constraints as the input gives them, RunInput::model_text). Positions, velocities and
// the run's length and outputs may differ.
std::uint64_t system_fingerprint(const System& system, const std::string& model);

}  // namespace deli
