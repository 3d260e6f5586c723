#pragma once

#include <array>
#include <cstdint>

namespace deli {

// Philox4x32-10 (Salmon et al., SC'11, the Random123 generator): a keyed bijection of a
// 128-bit counter. Counter-based, so a thermostat's noise is a pure function of (seed,
// step, atom id, draw): the same for any thread count or particle order, and a checkpoint
// needs only the seed and the step to continue the same random sequence.
using PhiloxCounter = std::array<std::uint32_t, 4>;
using PhiloxKey = std::array<std::uint32_t, 2>;
PhiloxCounter philox4x32_10(PhiloxCounter counter, PhiloxKey key);

// A stream of uniform and normal variates from consecutive counters: `start` with its last
// word increased by k = 0, 1, ... (leave its low 16 bits free for them).
class RandomStream {
 public:
  RandomStream(std::uint64_t seed, const PhiloxCounter& start);
  // In (0, 1): 53 random bits, never 0 (safe under log).
  double uniform();
  // Standard normal (Marsaglia's polar method on pairs of uniforms in (-1, 1); the second
  // value of a pair is kept for the next call).
  double normal();
  // Gamma(shape, 1) by Marsaglia and Tsang (2000); shape > 0.
  double gamma(double shape);

 private:
  void refill();
  double symmetric_uniform();

  PhiloxKey key_;
  PhiloxCounter counter_;
  std::array<std::uint32_t, 4> block_{};
  int used_ = 4;  // words of block_ already handed out
  bool has_spare_normal_ = false;
  double spare_normal_ = 0.0;
};

}  // namespace deli
