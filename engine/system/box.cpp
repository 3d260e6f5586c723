#include "system/box.hpp"

namespace deli {

Box::Box(Vec3 lo, Vec3 hi, std::array<bool, 3> periodic) : lo_(lo), hi_(hi), periodic_(periodic) {
  for (int a = 0; a < 3; ++a) {
    period_[a] = periodic_[a] ? hi_[a] - lo_[a] : 0.0;
    inverse_period_[a] = periodic_[a] ? 1.0 / period_[a] : 0.0;
  }
}

double Box::volume() const {
  const Vec3 l = length();
  return l.x * l.y * l.z;
}

Vec3 Box::unwrapped(const Vec3& x, const std::array<int, 3>& image) const {
  const Vec3 l = length();
  return {x.x + image[0] * l.x, x.y + image[1] * l.y, x.z + image[2] * l.z};
}

}  // namespace deli
