#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "constraints/constraint.hpp"
#include "neighbor/neighbor_list.hpp"
#include "system/particles.hpp"

namespace deli {

// A wall every particle must stay clear of (by its radius): a plane (point, unit normal
// pointing into the allowed side), or a sphere (centre `point`, `radius`) to stay inside
// or outside of.
struct Wall {
  ConstraintKind kind;  // plane, inside_sphere or outside_sphere
  Vec3 point;
  Vec3 normal;
  double radius = 0;
};

// The numbers the paper writes as "= 0": a constraint is active when |g| <= gap, and
// tangent when |grad g . v| <= velocity (reduced units, sigma and sigma/tau).
struct ConstraintTolerances {
  double gap = 1e-10;
  double velocity = 1e-10;
  double solver = 1e-12;  // position update residual, sigma
};

// Every constraint of a system: the equalities (rods, anchor strings), fixed for the run,
// and the inequalities found each step: hard-sphere pairs (all pairs not joined by a rod
// or bond, candidates from the neighbour list) and walls.
struct ConstraintSet {
  std::vector<Constraint> equalities;
  std::vector<Wall> walls;
  bool hard_spheres = false;
  std::vector<std::array<std::int32_t, 2>> unconstrained_pairs;  // sorted i < j: bonded pairs
  // Pairs the force field's neighbour list leaves out (1-3 and 1-4 neighbours under
  // special_bonds) that must still not overlap: checked every step.
  std::vector<std::array<std::int32_t, 2>> always_checked_pairs;
  ConstraintTolerances tolerances;
  // Replace every inequality by its linearisation about the previous step's configuration
  // (gaps linearised at the last converged state, as contact codes do): the paper's
  // counterexample, whose impulses no longer point along the current normals.
  bool linearized = false;

  bool empty() const { return equalities.empty() && walls.empty() && !hard_spheres; }
  // Largest contact distance r_i + r_j, for the neighbour list.
  double contact_reach(const Particles& particles) const;

  // Rows whose gap at q is at most `reach` (linearised about `linearize_about` if given):
  // the only rows a step moving no particle further than reach / 2 can close. Scanned once
  // per step instead of the whole neighbour list at every prediction.
  std::vector<Constraint> nearby_inequalities(const Particles& particles, const Vec3* q,
                                              const NeighborList& list, const Box& box,
                                              double reach,
                                              const Vec3* linearize_about = nullptr) const;
  // Among `rows`: those active at q (gap <= tolerance) or overlapping at `x`.
  std::vector<Constraint> active_among(const std::vector<Constraint>& rows, const Vec3* q,
                                       const Vec3* x, const Box& box) const;

  // The smallest inequality gap over every pair within reach and every wall (diagnostics).
  double minimum_gap(const Particles& particles, const Vec3* x, const NeighborList& list,
                     const Box& box) const;

  Constraint wall_row(const Wall& wall, std::int32_t i, double radius) const;
};

// The hard-sphere row of particles a < b: |x_a - x_b| - (r_a + r_b) >= 0.
Constraint sphere_pair(std::int32_t a, std::int32_t b, const Particles& particles);

}  // namespace deli
