#include "thermostats/random_stream.hpp"

#include <cmath>

#include "thermostats/polar_log.hpp"

namespace deli {

PhiloxCounter philox4x32_10(PhiloxCounter c, PhiloxKey k) {
  constexpr std::uint64_t multiplier0 = 0xD2511F53, multiplier1 = 0xCD9E8D57;
  constexpr std::uint32_t weyl0 = 0x9E3779B9, weyl1 = 0xBB67AE85;
  for (int round = 0; round < 10; ++round) {
    if (round > 0) k[0] += weyl0, k[1] += weyl1;
    const std::uint64_t p0 = multiplier0 * c[0];
    const std::uint64_t p1 = multiplier1 * c[2];
    c = {static_cast<std::uint32_t>(p1 >> 32) ^ c[1] ^ k[0], static_cast<std::uint32_t>(p1),
         static_cast<std::uint32_t>(p0 >> 32) ^ c[3] ^ k[1], static_cast<std::uint32_t>(p0)};
  }
  return c;
}

RandomStream::RandomStream(std::uint64_t seed, const PhiloxCounter& start)
    : key_{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)},
      counter_(start) {}

void RandomStream::refill() {
  block_ = philox4x32_10(counter_, key_);
  ++counter_[3];
  used_ = 0;
}

double RandomStream::uniform() {
  if (used_ > 2) refill();
  const std::uint64_t bits = (static_cast<std::uint64_t>(block_[used_]) << 32) | block_[used_ + 1];
  used_ += 2;
  // (bits >> 11) in [0, 2^53); + 0.5 keeps it off 0 and 1.
  return (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53;
}

double RandomStream::symmetric_uniform() {
  if (used_ > 3) refill();
  // 32 bits in (-1, 1), never 0: ample for the polar method's pairs.
  return (static_cast<double>(static_cast<std::int32_t>(block_[used_++])) + 0.5) * 0x1.0p-31;
}

double RandomStream::normal() {
  if (has_spare_normal_) {
    has_spare_normal_ = false;
    return spare_normal_;
  }
  // Marsaglia's polar method: no trigonometric functions, one logarithm per pair.
  for (;;) {
    const double u = symmetric_uniform(), v = symmetric_uniform();
    const double s = u * u + v * v;
    if (s >= 1.0) continue;
    const double factor = std::sqrt(-2.0 * polar_log(s) / s);
    spare_normal_ = v * factor;
    has_spare_normal_ = true;
    return u * factor;
  }
}

double RandomStream::gamma(double shape) {
  if (shape < 1.0) {
    // Gamma(a) = Gamma(a + 1) U^(1/a) (Marsaglia and Tsang, section 6).
    const double boost = std::pow(uniform(), 1.0 / shape);
    return gamma(shape + 1.0) * boost;
  }
  const double d = shape - 1.0 / 3.0;
  const double c = 1.0 / std::sqrt(9.0 * d);
  for (;;) {
    double x, v;
    do {
      x = normal();
      v = 1.0 + c * x;
    } while (v <= 0.0);
    v = v * v * v;
    const double u = uniform();
    if (std::log(u) < 0.5 * x * x + d - d * v + d * std::log(v)) return d * v;
  }
}

}  // namespace deli
