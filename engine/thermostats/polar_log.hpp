#pragma once

#include <cstdint>
#include <cstring>

namespace deli {

// The natural logarithm of the polar method's s (a finite normal double in (0, 1]; the
// thermostats' normals): fdlibm's e_log.c (Sun Microsystems, 1993), its three forms chosen by
// the same tests, in +, -, *, / and bit operations alone. Written so that a vector form can
// make the same numbers lane by lane (normal_triples' AVX2 form does; libm's log could only
// be called lane by lane, and took a quarter of a Langevin step's draws). Within one unit in
// the last place of libm's log (PolarLog.*).
namespace polar_log_constants {
constexpr double ln2_hi = 6.93147180369123816490e-01;  // 0x3fe62e42 fee00000
constexpr double ln2_lo = 1.90821492927058770002e-10;  // 0x3dea39ef 35793c76
constexpr double lg1 = 6.666666666666735130e-01;
constexpr double lg2 = 3.999999999940941908e-01;
constexpr double lg3 = 2.857142874366239149e-01;
constexpr double lg4 = 2.222219843214978396e-01;
constexpr double lg5 = 1.818357216161805012e-01;
constexpr double lg6 = 1.531383769920937332e-01;
constexpr double lg7 = 1.479819860511658591e-01;
constexpr double third = 0.33333333333333333;
}  // namespace polar_log_constants

inline double polar_log(double x) {
  using namespace polar_log_constants;
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const std::uint64_t high = (bits >> 32) & 0x000fffffu;  // the mantissa's upper 20 bits
  const std::uint64_t half = (high + 0x95f64u) & 0x100000u;
  // x scaled by a power of two into [sqrt(2)/2, sqrt(2)): 1 + f.
  const std::uint64_t scaled_bits = ((high | (half ^ 0x3ff00000u)) << 32) | (bits & 0xffffffffu);
  double scaled;
  std::memcpy(&scaled, &scaled_bits, sizeof scaled);
  const auto k = static_cast<std::int64_t>((bits >> 52) & 0x7ffu) - 1023 +
                 static_cast<std::int64_t>(half >> 20);
  const double dk = static_cast<double>(k);
  const double f = scaled - 1.0;
  if (((high + 2) & 0x000fffffu) < 3) {  // |f| < 2^-20
    const double r = f * f * (0.5 - third * f);
    return dk * ln2_hi - ((r - dk * ln2_lo) - f);
  }
  const double s = f / (2.0 + f);
  const double z = s * s;
  const double w = z * z;
  const double t1 = w * (lg2 + w * (lg4 + w * lg6));
  const double t2 = z * (lg1 + w * (lg3 + w * (lg5 + w * lg7)));
  const double r = t2 + t1;
  if (high >= 0x6147au && high <= 0x6b851u) {
    const double hfsq = 0.5 * f * f;
    return dk * ln2_hi - ((hfsq - (s * (hfsq + r) + dk * ln2_lo)) - f);
  }
  return dk * ln2_hi - ((s * (f - r) - dk * ln2_lo) - f);
}

}  // namespace deli
