#include "system/finite_state.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

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

namespace {
constexpr double kFarthest = 1e15, kMostPeriods = 1e9;
}  // namespace

std::optional<std::string> first_runaway_atom(const Particles& p, const Box& box) {
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

bool atoms_usable(const Particles& p, const Box& box, std::size_t begin, std::size_t end) {
  // A NaN fails every comparison, an infinity every bound: `<=` tests catch both.
  constexpr double kLargest = std::numeric_limits<double>::max();
  double most_periods[3];
  for (int a = 0; a < 3; ++a) most_periods[a] = box.periodic(a) ? kMostPeriods : kLargest;
  bool usable = true;
  for (std::size_t i = begin; i < end; ++i) {
    for (int a = 0; a < 3; ++a) {
      const double from_box = p.position[i][a] - box.lo()[a];
      usable &= std::abs(from_box) <= kFarthest;
      // Open axes have an inverse period of 0: no bound on periods there.
      usable &= std::abs(from_box * box.inverse_period()[a]) <= most_periods[a];
      usable &= std::abs(p.velocity[i][a]) <= kLargest;
    }
  }
  return usable;
}

}  // namespace deli
