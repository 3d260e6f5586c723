#pragma once

#include <cstddef>

// Eight doubles as one vector: GCC's (and Clang's) vector extension, element-wise IEEE
// operations at whatever width the target has (one AVX-512 register, two AVX halves, four
// SSE2 quarters). For the files built for the build machine's CPU (DELI_NATIVE) and their
// portable builds alike: the helpers have internal linkage, so no file shares inline code
// with a file built for another target.

// The helpers take and return vectors by value: internal and inlined, so the warning that
// such an ABI differs between targets concerns no call that exists.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace deli::lane_vectors {
namespace {

constexpr std::size_t width = 8;
typedef double Lanes __attribute__((vector_size(width * sizeof(double))));
typedef long LaneMask __attribute__((vector_size(width * sizeof(double))));
static_assert(sizeof(long) == sizeof(double));

inline Lanes load(const double* p) {
  Lanes v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void store(double* p, const Lanes& v) {
  __builtin_memcpy(p, &v, sizeof v);
}
inline Lanes broadcast(double v) {
  Lanes out;
  for (std::size_t l = 0; l < width; ++l) out[l] = v;
  return out;
}
// Entries k... of a then b (b's entry j as width + j): GCC's and Clang's two-source shuffles
// (the fuzzing build is Clang's). They move numbers without changing them.
template <long... k>
inline Lanes shuffle(const Lanes& a, const Lanes& b) {
  static_assert(sizeof...(k) == width);
#if defined(__clang__)
  return __builtin_shufflevector(a, b, k...);
#else
  return __builtin_shuffle(a, b, LaneMask{k...});
#endif
}

// Four doubles, half a Lanes: on a CPU with AVX2 and not AVX-512 (kQuarterLanes) an eight-lane
// vector is two registers, and a pass whose live vectors then outnumber AVX2's sixteen spills
// them; such passes work in Quarters there. Each lane's operations are the same either way.
typedef double Quarter __attribute__((vector_size(4 * sizeof(double))));
#if defined(__AVX2__) && !defined(__AVX512F__)
constexpr bool kQuarterLanes = true;
#else
constexpr bool kQuarterLanes = false;
#endif
template <class V>
constexpr std::size_t lanes_in = sizeof(V) / sizeof(double);
template <class V>
inline V load_as(const double* p) {
  V v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
template <class V>
inline void store_as(double* p, const V& v) {
  __builtin_memcpy(p, &v, sizeof v);
}
// shuffle()'s form for Quarters.
template <long... k>
inline Quarter shuffle4(const Quarter& a, const Quarter& b) {
  static_assert(sizeof...(k) == 4);
#if defined(__clang__)
  return __builtin_shufflevector(a, b, k...);
#else
  typedef long QuarterMask __attribute__((vector_size(4 * sizeof(double))));
  return __builtin_shuffle(a, b, QuarterMask{k...});
#endif
}

}  // namespace
}  // namespace deli::lane_vectors
