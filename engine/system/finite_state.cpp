#include "system/finite_state.hpp"

#include <cmath>
#include <cstdio>

namespace deli {

namespace {
bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string described(const Particles& p, std::size_t i, const char* what, const Vec3& v) {
  char text[160];
  std::snprintf(text, sizeof text, "atom %lld: %s (%g, %g, %g)", static_cast<long long>(p.id[i]),
                what, v.x, v.y, v.z);
  return text;
}
}  // namespace

std::optional<std::string> first_non_finite_atom(const Particles& p,
                                                 const std::vector<Vec3>* forces) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!finite(p.position[i])) return described(p, i, "position", p.position[i]);
    if (!finite(p.velocity[i])) return described(p, i, "velocity", p.velocity[i]);
    if (forces && i < forces->size() && !finite((*forces)[i])) {
      return described(p, i, "force", (*forces)[i]);
    }
  }
  return std::nullopt;
}

std::optional<std::string> first_runaway_atom(const Particles& p, const Box& box) {
  constexpr double kFarthest = 1e15, kMostPeriods = 1e9;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const double from_box = p.position[i][a] - box.lo()[a];
      const bool away =
          !(std::abs(from_box) <= kFarthest) ||
          (box.periodic(a) && !(std::abs(from_box * box.inverse_period()[a]) <= kMostPeriods));
      if (away) return described(p, i, "position", p.position[i]);
    }
  }
  return std::nullopt;
}

}  // namespace deli
