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

// One chunk of a half list for a vector pair loop: slots first..last-1 with their listed
// partners (slots) and image codes, positions and forces by slot. Slot i's partners are
// list[offsets[i] .. ends[i]), or without `ends` list[offsets[i] .. offsets[i + 1]).
struct VectorPairChunk {
  const PaddedVec3* x;
  PaddedVec3* f;
  const std::int32_t* list;
  const std::uint8_t* codes;
  const std::size_t* offsets;
  const Vec3* shifts;  // the list's 27 image shifts
  std::int32_t first, last;
  const std::size_t* ends = nullptr;
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

// One chunk of a half list in list order for the shadow energy's curvature sum: particles
// first..last-1 with their listed partners, separations by minimum-image rounding (as
// Box::minimum_image) in a box of the given periods.
struct CurvatureChunk {
  const Vec3* x;
  const Vec3* v;
  const std::int32_t* list;
  const std::size_t* offsets;
  Vec3 period, inverse_period;
  std::size_t first, last;
  const std::size_t* ends = nullptr;  // as VectorPairChunk::ends
};

// An evaluator with a vector form of PairForce's curvature sum for one type pair:
// curvature_loop() returns the sum over the chunk's pairs in reach of phi'' (u.w)^2 -
// (f/r) (|w|^2 - (u.w)^2) (w = v_i - v_j), each term the scalar one's bits, added one at a
// time in list order from +0 (the scalar sum's bits), where curvature_loop_built().
template <class E>
concept VectorCurvatureEvaluator = requires(const typename E::Params& p, const CurvatureChunk& c) {
  { E::curvature_loop_built() } -> std::same_as<bool>;
  { E::curvature_loop(p, c) } -> std::same_as<double>;
};

}  // namespace deli
