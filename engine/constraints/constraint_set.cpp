#include "constraints/constraint_set.hpp"

#include <algorithm>
#include <limits>

#include "core/parallel.hpp"

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

void ConstraintSet::renumber(const std::vector<std::int32_t>& now) {
  for (Constraint& c : equalities) {
    if (c.i >= 0) c.i = now[static_cast<std::size_t>(c.i)];
    if (c.j >= 0) c.j = now[static_cast<std::size_t>(c.j)];
    if (c.kind == ConstraintKind::rod && c.i > c.j) std::swap(c.i, c.j);
  }
  for (auto* pairs : {&unconstrained_pairs, &always_checked_pairs}) {
    for (auto& [a, b] : *pairs) {
      a = now[static_cast<std::size_t>(a)];
      b = now[static_cast<std::size_t>(b)];
      if (a > b) std::swap(a, b);
    }
    std::sort(pairs->begin(), pairs->end());
  }
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

// for_each_inequality's rows, in chunks of particles (a pair with the particle that lists it,
// a wall's row with its particle), each bounded by its own running minimum: every gap below
// the bound is evaluated exactly, so the minimum is the serial loop's on any number of
// threads. A pair is looked up among the bonded pairs only when its gap is below the bound
// (a few times a chunk, not at each of the list's pairs). Taken at every thermo sample; on
// one thread, the default input's 30000 listed pairs took 2 % of its two-thread loop.
double ConstraintSet::minimum_gap(const Particles& particles, const Vec3* x,
                                  const NeighborList& list, const Box& box) const {
  constexpr double none = std::numeric_limits<double>::infinity();
  const std::size_t n = particles.size();
  const int chunks = chunks_for(n);
  std::vector<double> chunk_smallest(static_cast<std::size_t>(chunks), none);
  const NeighborList::PartnerRanges ranges =
      hard_spheres ? list.partner_ranges() : NeighborList::PartnerRanges{};
  for_each_chunk(n, chunks, [&](int chunk, std::size_t begin, std::size_t end) {
    double smallest = none;
    if (hard_spheres) {
      if (chunk == 0) {
        for (const auto& [a, b] : always_checked_pairs) {
          smallest =
              std::min(smallest, gap_unless_beyond(sphere_pair(a, b, particles), x, box, smallest));
        }
      }
      const std::int32_t* neighbors = ranges.neighbors;
      for (std::size_t i = begin; i < std::min(end, ranges.particles); ++i) {
        for (std::size_t k = ranges.begin[i]; k < ranges.end[i]; ++k) {
          const auto a = static_cast<std::int32_t>(std::min<std::size_t>(i, neighbors[k]));
          const auto b = static_cast<std::int32_t>(std::max<std::size_t>(i, neighbors[k]));
          const double gap = gap_unless_beyond(sphere_pair(a, b, particles), x, box, smallest);
          if (gap < smallest &&
              !std::binary_search(unconstrained_pairs.begin(), unconstrained_pairs.end(),
                                  std::array<std::int32_t, 2>{a, b})) {
            smallest = gap;
          }
        }
      }
    }
    for (const Wall& wall : walls) {
      for (std::size_t i = begin; i < end; ++i) {
        const Constraint c = wall_row(wall, static_cast<std::int32_t>(i), particles.radius[i]);
        smallest = std::min(smallest, gap_unless_beyond(c, x, box, smallest));
      }
    }
    chunk_smallest[static_cast<std::size_t>(chunk)] = smallest;
  });
  double smallest = none;
  for (const double s : chunk_smallest) smallest = std::min(smallest, s);
  return smallest;
}

}  // namespace deli
