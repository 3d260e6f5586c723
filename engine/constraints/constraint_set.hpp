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

// Every iteration limit of the constraint solvers, beside the tolerances they iterate to.
// Each hit is either a counted fallback (the step goes on; a thermo/H5MD counter says how
// often) or a stop naming the step, the cluster and the residual (README, "Solver
// limits"). Input: [constraints.limits].
struct SolverLimits {
  // Position update, Newton iterations per cluster. Stop (problem dumped).
  int newton = 50;
  // Backtracking halvings of one Newton step's line search; when none decreases the merit
  // the solve stops there: a stop as above unless the residual is already within tolerance.
  int line_search = 34;
  // Extended active set, rounds of reflect-and-predict. Fallback: the rows found so far go
  // on; the feasibility guard lands any the last prediction missed (`active_set_caps`).
  int active_set_rounds = 16;
  // Feasibility guard, rounds of landing overlapped rows. Fallback: the step ends
  // overlapped (`feasibility_caps`, and `penetrating_steps` when beyond the gap tolerance).
  int feasibility_rounds = 8;
  // Reflection (Algorithm 2), solves per cluster. Fallback: inelastic projection
  // (`stalled_reflections`).
  int reflection_solves = 100;
  // Each reflection's non-negative QP (Lawson-Hanson), iterations per solve; 0 (not an
  // input value): 10 n + 10 for n rows (finite termination takes about n; the guard against
  // cycling at a degenerate vertex a few more). Fallback: see reflect() (`qp_caps`).
  int qp_iterations = 0;
  // The implicit midpoint's fixed point (midpoint Lagrangian, direct and collision
  // baselines), passes per step. Stop.
  int midpoint_passes = 200;
  // The collision baseline's contact-time root finder, iterations per row. Fallback: the
  // bracket's feasible end (`contact_time_caps`).
  int contact_time = 200;
  // The direct baselines: passes moving the constraint gradients to the landed point, and
  // rounds adding newly overlapped rows. Stop.
  int direct_settle_passes = 100;
  int direct_landing_rounds = 16;
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
  SolverLimits limits;
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

  // The same constraints once particle i has become particle now[i] (system/particle_order):
  // pairs as i < j again, the lists of pairs sorted again; the equalities keep their order.
  void renumber(const std::vector<std::int32_t>& now);
};

// The hard-sphere row of particles a < b: |x_a - x_b| - (r_a + r_b) >= 0.
Constraint sphere_pair(std::int32_t a, std::int32_t b, const Particles& particles);

}  // namespace deli
