#include "constraints/constraint_set.hpp"

#include <algorithm>
#include <limits>

namespace deli {

double ConstraintSet::contact_reach(const Particles& particles) const {
  if (!hard_spheres) return 0.0;
  double r = 0.0;
  for (double radius : particles.radius) r = std::max(r, radius);
  return 2.0 * r;
}

Constraint ConstraintSet::wall_row(const Wall& wall, std::int32_t i, double radius) const {
  Constraint c;
  c.kind = wall.kind;
  c.i = i;
  c.point = wall.point;
  c.normal = wall.normal;
  switch (wall.kind) {
    case ConstraintKind::plane:
      c.length = radius;
      break;
    case ConstraintKind::inside_sphere:
      c.length = wall.radius - radius;
      break;
    default:
      c.length = wall.radius + radius;
      break;
  }
  return c;
}

Constraint sphere_pair(std::int32_t a, std::int32_t b, const Particles& particles) {
  Constraint c;
  c.kind = ConstraintKind::sphere_pair;
  c.i = a;
  c.j = b;
  c.length = particles.radius[a] + particles.radius[b];
  return c;
}

namespace {

// Visits every hard-sphere pair of the neighbour list that is not bonded, and every
// (particle, wall) row.
template <class Visit>
void for_each_inequality(const ConstraintSet& set, const Particles& particles,
                         const NeighborList& list, Visit&& visit) {
  if (set.hard_spheres) {
    for (const auto& [a, b] : set.always_checked_pairs) visit(sphere_pair(a, b, particles));
    const NeighborList::PartnerRanges ranges = list.partner_ranges();
    const std::int32_t* neighbors = ranges.neighbors;
    for (std::size_t i = 0; i < ranges.particles; ++i) {
      for (std::size_t k = ranges.begin[i]; k < ranges.end[i]; ++k) {
        const auto a = static_cast<std::int32_t>(std::min<std::size_t>(i, neighbors[k]));
        const auto b = static_cast<std::int32_t>(std::max<std::size_t>(i, neighbors[k]));
        if (std::binary_search(set.unconstrained_pairs.begin(), set.unconstrained_pairs.end(),
                               std::array<std::int32_t, 2>{a, b})) {
          continue;
        }
        visit(sphere_pair(a, b, particles));
      }
    }
  }
  for (const Wall& wall : set.walls) {
    for (std::size_t i = 0; i < particles.size(); ++i) {
      visit(set.wall_row(wall, static_cast<std::int32_t>(i), particles.radius[i]));
    }
  }
}
}  // namespace

std::vector<Constraint> ConstraintSet::nearby_inequalities(const Particles& particles,
                                                           const Vec3* q, const NeighborList& list,
                                                           const Box& box, double reach,
                                                           const Vec3* linearize_about) const {
  std::vector<Constraint> nearby;
  if (linearize_about) {
    for_each_inequality(*this, particles, list, [&](const Constraint& original) {
      const Constraint c = deli::linearized(original, linearize_about, box);
      if (evaluate(c, q, box).gap <= reach) nearby.push_back(c);
    });
    return nearby;
  }
  // The same rows in the same order as visiting every inequality, but a pair is first
  // screened by its squared distance, with a margin far above rounding so that no pair the
  // exact test (|d| - contact <= reach) keeps is dropped; only the few pairs left take the
  // square root and the search among bonded pairs.
  if (hard_spheres) {
    for (const auto& [a, b] : always_checked_pairs) {
      const Constraint c = sphere_pair(a, b, particles);
      if (evaluate(c, q, box).gap <= reach) nearby.push_back(c);
    }
    const NeighborList::PartnerRanges ranges = list.partner_ranges();
    const std::int32_t* neighbors = ranges.neighbors;
    const std::vector<double>& radius = particles.radius;
    for (std::size_t i = 0; i < ranges.particles; ++i) {
      for (std::size_t k = ranges.begin[i]; k < ranges.end[i]; ++k) {
        const auto a = static_cast<std::int32_t>(std::min<std::size_t>(i, neighbors[k]));
        const auto b = static_cast<std::int32_t>(std::max<std::size_t>(i, neighbors[k]));
        const double within = radius[a] + radius[b] + reach;
        if (norm2(box.minimum_image(q[a] - q[b])) > within * within * (1.0 + 1e-6) + 1e-300) {
          continue;
        }
        if (std::binary_search(unconstrained_pairs.begin(), unconstrained_pairs.end(),
                               std::array<std::int32_t, 2>{a, b})) {
          continue;
        }
        const Constraint c = sphere_pair(a, b, particles);
        if (evaluate(c, q, box).gap <= reach) nearby.push_back(c);
      }
    }
  }
  for (const Wall& wall : walls) {
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const Constraint c = wall_row(wall, static_cast<std::int32_t>(i), particles.radius[i]);
      if (evaluate(c, q, box).gap <= reach) nearby.push_back(c);
    }
  }
  return nearby;
}

std::vector<Constraint> ConstraintSet::active_among(const std::vector<Constraint>& rows,
                                                    const Vec3* q, const Vec3* x,
                                                    const Box& box) const {
  std::vector<Constraint> active;
  for (const Constraint& c : rows) {
    if (evaluate(c, q, box).gap <= tolerances.gap || evaluate(c, x, box).gap <= 0.0) {
      active.push_back(c);
    }
  }
  return active;
}

double ConstraintSet::minimum_gap(const Particles& particles, const Vec3* x,
                                  const NeighborList& list, const Box& box) const {
  double smallest = std::numeric_limits<double>::infinity();
  for_each_inequality(*this, particles, list, [&](const Constraint& c) {
    smallest = std::min(smallest, gap_unless_beyond(c, x, box, smallest));
  });
  return smallest;
}

}  // namespace deli
