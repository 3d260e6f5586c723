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

}  // namespace
}  // namespace deli::lane_vectors
