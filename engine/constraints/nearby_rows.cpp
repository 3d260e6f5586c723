#include "constraints/nearby_rows.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

namespace deli {

void NearbyRows::make(const ConstraintSet& set, const Particles& particles, const Vec3* q,
                      const NeighborList& list, const Box& box) {
  pairs_.clear();
  bounds_.clear();
  const auto& offsets = list.offsets();
  const auto& neighbors = list.neighbors();
  const std::vector<double>& radius = particles.radius;
  const std::vector<std::uint8_t>& codes = list.image_codes();
  shifted_ = !codes.empty();
  const bool bonded_pairs = !set.unconstrained_pairs.empty();
  if (bonded_pairs) index_bonded_pairs(set, particles.size());
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
    for (std::size_t k = offsets[i]; k < offsets[i + 1]; ++k) {
      const auto a = static_cast<std::int32_t>(std::min<std::size_t>(i, neighbors[k]));
      const auto b = static_cast<std::int32_t>(std::max<std::size_t>(i, neighbors[k]));
      Vec3 shift;
      if (shifted_) {
        // The list's shift is for q_i - q_j: negated when i is the pair's second particle.
        shift = list.image_shifts()[codes[k]];
        if (a != static_cast<std::int32_t>(i)) shift = -shift;
      }
      // Through the list's shift, as collect() measures (the minimum image up to rounding).
      // Generous by far more than rounding: no pair within contact + margin is dropped.
      const double d2 =
          shifted_ ? norm2(q[a] - q[b] - shift) : norm2(box.minimum_image(q[a] - q[b]));
      const double contact = radius[a] + radius[b];
      const double within = contact + margin_;
      if (d2 > within * within * (1.0 + 1e-6) + 1e-300) continue;
      if (bonded_pairs && bonded(a, b)) continue;
      pairs_.push_back({a, b, contact, std::sqrt(d2) - contact, shift});
      bounds_.push_back({a, b, pairs_.back().anchor_gap});
    }
  }
  anchor_.assign(q, q + particles.size());
  moved_.assign(particles.size(), 0.0);
  list_ = &list;
  list_builds_ = list.builds();
}

void NearbyRows::index_bonded_pairs(const ConstraintSet& set, std::size_t particle_count) {
  const auto& pairs = set.unconstrained_pairs;
  if (bonded_source_ == &pairs && bonded_count_ == pairs.size() &&
      bonded_first_.size() == particle_count + 1) {
    return;
  }
  // Sorted by (a, b): each a's partners are one ascending run.
  bonded_first_.assign(particle_count + 1, 0);
  for (const auto& [a, b] : pairs) ++bonded_first_[a + 1];
  for (std::size_t i = 0; i < particle_count; ++i) bonded_first_[i + 1] += bonded_first_[i];
  bonded_partner_.resize(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) bonded_partner_[k] = pairs[k][1];
  bonded_source_ = &pairs;
  bonded_count_ = pairs.size();
}

bool NearbyRows::bonded(std::int32_t a, std::int32_t b) const {
  for (std::int32_t k = bonded_first_[a]; k < bonded_first_[a + 1]; ++k) {
    if (bonded_partner_[k] == b) return true;
  }
  return false;
}

void NearbyRows::collect(const ConstraintSet& set, const Particles& particles, const Vec3* q,
                         const NeighborList& list, const Box& box, double reach,
                         const double* particle_reach, double exact_below,
                         std::vector<Constraint>& out, std::vector<double>& gap_at_q) {
  out.clear();
  gap_at_q.clear();
  auto keep = [&](const Constraint& c, double row_reach) {
    const double gap = evaluate(c, q, box).gap;
    if (gap <= row_reach) out.push_back(c), gap_at_q.push_back(gap);
  };
  // A row's reach: the pair's two particle reaches (a wall row's: twice its particle's),
  // or the one reach for all.
  auto pair_reach = [&](std::int32_t a, std::int32_t b) {
    return particle_reach ? particle_reach[a] + particle_reach[b] : reach;
  };
  if (set.hard_spheres) {
    for (const auto& [a, b] : set.always_checked_pairs) {
      keep(sphere_pair(a, b, particles), pair_reach(a, b));
    }
    bool fresh = list_ == &list && list_builds_ == list.builds() &&
                 anchor_.size() == particles.size() && reach < margin_;
    if (fresh) {
      // The squares first, then the roots as packets (std::sqrt, which may set errno, does
      // not vectorise).
      double largest2 = 0.0;
      const std::size_t count = anchor_.size();
      const Vec3* anchor = anchor_.data();
      double* moved = moved_.data();
      for (std::size_t i = 0; i < count; ++i) {
        moved[i] = norm2(q[i] - anchor[i]);
        largest2 = std::max(largest2, moved[i]);
      }
      Eigen::Map<Eigen::ArrayXd> distance(moved, static_cast<Eigen::Index>(count));
      if (particle_reach) {
        distance = distance.sqrt() + Eigen::Map<const Eigen::ArrayXd>(
                                         particle_reach, static_cast<Eigen::Index>(count));
      } else {
        distance = distance.sqrt();
      }
      // reach + 2 s <= margin, with room for rounding.
      const double room = 0.5 * (margin_ - reach) * (1.0 - 1e-6);
      fresh = largest2 <= room * room;
    }
    if (!fresh) {
      make(set, particles, q, list, box);
      if (particle_reach) moved_.assign(particle_reach, particle_reach + particles.size());
    }
    // The screen of nearby_inequalities, then its exact test (evaluate()'s sphere-pair gap,
    // the row built only when kept). The screen may take the separation through the list's
    // shift (no rounding to the nearest image): it differs from the minimum image by
    // rounding at most, far inside the screen's margin. A pair inside contact + reach by
    // far more than rounding is kept without its square root, and its gap is needed only
    // if it may be at most `exact_below`.
    const double screen = 1.0 + 1e-6, sure = 1.0 - 1e-6;
    const double infinity = std::numeric_limits<double>::infinity();
    // A pair whose gap at q is certainly beyond the reach (its anchor gap less both
    // displacements exceeds it by far more than rounding) is one the exact test drops too.
    // The others' indices are gathered first without a branch (about half the pairs pass,
    // unpredictably), then, again without a branch, those within the screen with their
    // squared distances, which are then tested in order. With particle reaches, `moved_`
    // holds each particle's displacement plus its reach.
    const double beyond = (particle_reach ? 0.0 : reach) + 1e-9;
    const double* moved = moved_.data();
    const std::size_t pair_count = bounds_.size();
    near_.resize(pair_count);
    near_d2_.resize(pair_count);
    std::size_t count = 0;
    for (std::size_t k = 0; k < pair_count; ++k) {
      const PairBound& bound = bounds_[k];
      near_[count] = static_cast<std::int32_t>(k);
      count += !(bound.anchor_gap - moved[bound.a] - moved[bound.b] > beyond) ? 1 : 0;
    }
    std::size_t within_count = 0;
    auto screen_pair = [&](std::int32_t k, double d2) {
      const double within = pairs_[k].contact + pair_reach(pairs_[k].a, pairs_[k].b);
      near_[within_count] = k;
      near_d2_[within_count] = d2;
      within_count += !(d2 > within * within * screen + 1e-300) ? 1 : 0;
    };
    if (shifted_) {
      for (std::size_t m = 0; m < count; ++m) {
        const Pair& pair = pairs_[near_[m]];
        screen_pair(near_[m], norm2(q[pair.a] - q[pair.b] - pair.shift));
      }
    } else {
      for (std::size_t m = 0; m < count; ++m) {
        const Pair& pair = pairs_[near_[m]];
        screen_pair(near_[m], norm2(box.minimum_image(q[pair.a] - q[pair.b])));
      }
    }
    for (std::size_t m = 0; m < within_count; ++m) {
      const Pair& pair = pairs_[near_[m]];
      const double d2 = near_d2_[m];
      const double row_reach = pair_reach(pair.a, pair.b);
      const double within = pair.contact + row_reach;
      const double near = pair.contact + exact_below;
      double gap = infinity;
      if (!(d2 <= within * within * sure) || exact_below < -0.5 * pair.contact ||
          d2 <= near * near * screen + 1e-300) {
        gap = norm(box.minimum_image(q[pair.a] - q[pair.b])) - pair.contact;
        if (!(gap <= row_reach)) continue;
      }
      // sphere_pair(a, b)'s row, made in place (its contact is the pair's).
      Constraint& row = out.emplace_back();
      row.kind = ConstraintKind::sphere_pair;
      row.i = pair.a;
      row.j = pair.b;
      row.length = pair.contact;
      gap_at_q.push_back(gap);
    }
  }
  for (const Wall& wall : set.walls) {
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const auto index = static_cast<std::int32_t>(i);
      const double row_reach = particle_reach ? 2.0 * particle_reach[i] : reach;
      if (wall.kind == ConstraintKind::plane) {
        // evaluate()'s plane gap, without building the row first.
        if (dot(wall.normal, q[i] - wall.point) - particles.radius[i] > row_reach) continue;
      }
      keep(set.wall_row(wall, index, particles.radius[i]), row_reach);
    }
  }
}

}  // namespace deli
