#pragma once

#include <concepts>
#include <cstdint>

#include "core/vec3.hpp"

namespace deli {

// A position or force padded to four doubles (32 bytes, aligned): one 256-bit load or store
// per particle in a vector pair loop, which gathers a vector's partners by loads and
// transposes and adds their forces back one 256-bit store each.
struct alignas(32) PaddedVec3 {
  double x = 0.0, y = 0.0, z = 0.0, pad = 0.0;
  PaddedVec3& operator+=(const PaddedVec3& o) {
    x += o.x, y += o.y, z += o.z;
    return *this;
  }
};

// One chunk of a cell-ordered half list for a vector pair loop: slots first..last-1 with
// their listed partners (slots) and image codes, positions and forces by slot.
struct VectorPairChunk {
  const PaddedVec3* x;
  PaddedVec3* f;
  const std::int32_t* list;
  const std::uint8_t* codes;
  const std::size_t* offsets;
  const Vec3* shifts;  // the list's 27 image shifts
  std::int32_t first, last;
};

// An evaluator with a vector form of PairForce's loop for one type pair and image-coded
// lists: vector_loop() runs a chunk (forces added to chunk.f, the virial to `virial` when
// tallying; returns the energy when tallying) by vector where vector_loop_built() (the
// CPU's instruction set under DELI_NATIVE), else with the same sums one pair at a time.
template <class E>
concept VectorPairEvaluator = requires(const typename E::Params& p, const VectorPairChunk& chunk,
                                       SymTensor& w) {
  { E::vector_loop_built() } -> std::same_as<bool>;
  { E::vector_loop(p, chunk, true, w) } -> std::same_as<double>;
};

}  // namespace deli
