#pragma once

#include <array>
#include <cmath>

#include "core/vec3.hpp"

namespace deli {

// Orthorhombic box [lo, hi), periodic or open per axis. Along an open axis the bounds
// only define the volume used for pressure; particles may leave them.
class Box {
 public:
  Box() = default;
  Box(Vec3 lo, Vec3 hi, std::array<bool, 3> periodic);

  const Vec3& lo() const { return lo_; }
  const Vec3& hi() const { return hi_; }
  Vec3 length() const { return hi_ - lo_; }
  bool periodic(int axis) const { return periodic_[axis]; }
  const std::array<bool, 3>& periodic() const { return periodic_; }
  double volume() const;

  // Lengths and inverse lengths with zeros on open axes, so that
  // d -= period * nearbyint(d * inverse_period) is the minimum image without a branch.
  const Vec3& period() const { return period_; }
  const Vec3& inverse_period() const { return inverse_period_; }

  // Exact for any finite separation (std::nearbyint would be a library call per pair
  // without SSE4.1; the integer conversion is a single instruction). A non-finite
  // separation stays non-finite, for the caller's checks to report.
  Vec3 minimum_image(Vec3 d) const {
    d.x -= period_.x * round_to_integer(d.x * inverse_period_.x);
    d.y -= period_.y * round_to_integer(d.y * inverse_period_.y);
    d.z -= period_.z * round_to_integer(d.z * inverse_period_.z);
    return d;
  }
  // Half away from zero. From 2^52 up every double is an integer already (and x + 0.5 could
  // round up to the next one); NaN, infinities and magnitudes from 2^63 up would make the
  // conversion undefined: all of them are returned as they are. Selects, not branches: this
  // runs per axis per pair in the candidate scans.
  static double round_to_integer(double x) {
    const bool convertible = std::abs(x) < 0x1p52;  // false for NaN
    const auto whole = static_cast<long long>(convertible ? x + std::copysign(0.5, x) : 0.0);
    return convertible ? static_cast<double>(whole) : x;
  }

  // Maps x into [lo, hi) along periodic axes and counts the crossings in image. Inline: the
  // neighbour list's builds wrap every particle twice, and called, each wrap reloaded the
  // box's numbers (the 4000-sphere fluid on one thread: 3 % of its loop).
  void wrap(Vec3& x, std::array<int, 3>& image) const {
    for (int a = 0; a < 3; ++a) {
      if (!periodic_[a]) continue;
      const double shift = std::floor((x[a] - lo_[a]) * inverse_period_[a]);
      if (shift != 0.0) {
        x[a] -= shift * period_[a];
        image[a] += static_cast<int>(shift);
      }
      // Rounding can leave x == hi exactly; hi belongs to the next image.
      if (x[a] >= hi_[a]) {
        x[a] -= period_[a];
        image[a] += 1;
      }
    }
  }
  // Position with periodic crossings undone.
  Vec3 unwrapped(const Vec3& x, const std::array<int, 3>& image) const;

 private:
  Vec3 lo_, hi_{1, 1, 1};
  std::array<bool, 3> periodic_{true, true, true};
  Vec3 period_{1, 1, 1}, inverse_period_{1, 1, 1};
};

}  // namespace deli
