#include "constraints/nearby_rows.hpp"

#include <algorithm>
#include <cmath>

namespace deli {

void NearbyRows::make(const ConstraintSet& set, const Particles& particles, const Vec3* q,
                      const NeighborList& list, const Box& box) {
  pairs_.clear();
  const auto& offsets = list.offsets();
  const auto& neighbors = list.neighbors();
  const std::vector<double>& radius = particles.radius;
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
    for (std::size_t k = offsets[i]; k < offsets[i + 1]; ++k) {
      const auto a = static_cast<std::int32_t>(std::min<std::size_t>(i, neighbors[k]));
      const auto b = static_cast<std::int32_t>(std::max<std::size_t>(i, neighbors[k]));
      // Generous by far more than rounding: no pair within contact + margin is dropped.
      const double within = radius[a] + radius[b] + margin_;
      if (norm2(box.minimum_image(q[a] - q[b])) > within * within * (1.0 + 1e-6) + 1e-300) {
        continue;
      }
      if (std::binary_search(set.unconstrained_pairs.begin(), set.unconstrained_pairs.end(),
                             std::array<std::int32_t, 2>{a, b})) {
        continue;
      }
      pairs_.push_back({a, b});
    }
  }
  anchor_.assign(q, q + particles.size());
  list_ = &list;
  list_builds_ = list.builds();
}

void NearbyRows::collect(const ConstraintSet& set, const Particles& particles, const Vec3* q,
                         const NeighborList& list, const Box& box, double reach,
                         std::vector<Constraint>& out) {
  out.clear();
  if (set.hard_spheres) {
    for (const auto& [a, b] : set.always_checked_pairs) {
      const Constraint c = sphere_pair(a, b, particles);
      if (evaluate(c, q, box).gap <= reach) out.push_back(c);
    }
    bool fresh = list_ == &list && list_builds_ == list.builds() &&
                 anchor_.size() == particles.size() && reach < margin_;
    if (fresh) {
      double largest2 = 0.0;
      for (std::size_t i = 0; i < anchor_.size(); ++i) {
        largest2 = std::max(largest2, norm2(q[i] - anchor_[i]));
      }
      // reach + 2 s <= margin, with room for rounding.
      const double room = 0.5 * (margin_ - reach) * (1.0 - 1e-6);
      fresh = largest2 <= room * room;
    }
    if (!fresh) make(set, particles, q, list, box);
    const std::vector<double>& radius = particles.radius;
    for (const auto& [a, b] : pairs_) {
      // The screen of nearby_inequalities, then its exact test.
      const double within = radius[a] + radius[b] + reach;
      if (norm2(box.minimum_image(q[a] - q[b])) > within * within * (1.0 + 1e-6) + 1e-300) {
        continue;
      }
      const Constraint c = sphere_pair(a, b, particles);
      if (evaluate(c, q, box).gap <= reach) out.push_back(c);
    }
  }
  for (const Wall& wall : set.walls) {
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const auto index = static_cast<std::int32_t>(i);
      if (wall.kind == ConstraintKind::plane) {
        // evaluate()'s plane gap, without building the row first.
        if (dot(wall.normal, q[i] - wall.point) - particles.radius[i] > reach) continue;
      }
      const Constraint c = set.wall_row(wall, index, particles.radius[i]);
      if (evaluate(c, q, box).gap <= reach) out.push_back(c);
    }
  }
}

}  // namespace deli
