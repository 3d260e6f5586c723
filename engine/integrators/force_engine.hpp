#pragma once

#include <optional>
#include <utility>
#include <vector>

#include "core/range_pass.hpp"
#include "forces/force_field.hpp"
#include "neighbor/neighbor_list.hpp"
#include "system/system.hpp"

namespace deli {

// Keeps the neighbour list in step with the particles and evaluates the force field:
// what every integrator calls once per force evaluation.
class ForceEngine {
 public:
  // The neighbour list reaches at least `minimum_cutoff` (hard-sphere contacts) beyond the
  // force field's own cutoff.
  ForceEngine(const ForceField& force_field, double skin, double minimum_cutoff = 0.0);

  // Rebuilds the neighbour list when needed (wrapping positions into the box first, the
  // only time they are wrapped) and computes forces and energies.
  // Energies and virial only when `tally` (thermo steps).
  const ForceEvaluation& compute(System& system, bool tally = true);
  // The same, `listed`: the caller has found (in a pass of its own, with NeighborList's
  // per-particle test) that the list stays valid at the system's positions.
  const ForceEvaluation& compute(System& system, bool tally, bool listed);

  // Forces (only) at positions x instead of the system's, through the current neighbour
  // list, which the caller has checked covers x.
  void forces_at(System& system, const std::vector<Vec3>& x, std::vector<Vec3>& force) const;

  // Rebuilds the neighbour list (wrapping positions) if the particles have moved too far,
  // or always when `force`.
  bool ensure_neighbors(System& system, bool force = false);
  // ensure_neighbors, with `after_wrap` run on each chunk of the particles after its check
  // and wrap, in the build's first job, where a build runs (a caller's pass over the wrapped
  // positions: a job fewer).
  bool ensure_neighbors(System& system, bool force, const RangePass* after_wrap);
  // Rebuilds the list from `build_positions` (a checkpoint's), leaving the system's own.
  void restore_neighbors(System& system, const std::vector<Vec3>& build_positions);
  // Counts builds on from `builds` (an engine that takes over from another's).
  void continue_build_count(std::int64_t builds) { neighbors_.continue_build_count(builds); }
  // The list's cell stencils, handed from an engine to its successor (NeighborList::Stencils).
  NeighborList::Stencils take_list_stencils() { return neighbors_.take_stencils(); }
  void adopt_list_stencils(NeighborList::Stencils stencils) {
    neighbors_.adopt_stencils(std::move(stencils));
  }
  // Whether the current list also holds every pair within reach at positions x.
  bool neighbors_cover(const std::vector<Vec3>& x) const { return !neighbors_.needs_rebuild(x); }

  const std::vector<Vec3>& force() const { return force_; }
  // Whether compute() for `particle_count` particles leaves force() as it is: zeros, from a
  // force field without terms.
  bool forces_stay(std::size_t particle_count) const {
    return force_field_.terms().empty() && force_zero_ && force_.size() == particle_count;
  }
  const ForceEvaluation& last() const { return last_; }
  const NeighborList& neighbors() const { return neighbors_; }
  const ForceField& force_field() const { return force_field_; }
  // Verlet's modified energy at the last evaluation (which must have tallied energies).
  std::optional<double> verlet_shadow_energy(const System& system, double h) const;

 private:
  const ForceField& force_field_;
  NeighborList neighbors_;
  std::vector<Vec3> force_;
  // force_ holds zeros from a force field without terms (nothing else writes it): a hard-sphere
  // fluid's evaluations then zero nothing again (a job of the team a step).
  bool force_zero_ = false;
  ForceEvaluation last_;
};

// Exclusions and scaled pairs implied by the topology and the special_bonds factors.
std::vector<std::array<std::int32_t, 2>> special_exclusions(const SpecialPairs& special,
                                                            const std::array<double, 3>& factors);

// Verlet's modified energy to O(h^2), H - h^2/24 F.M^-1.F + h^2/12 v.V''.v, from its parts
// (force_term = F.M^-1.F, curvature = v.V''.v), summed in this one order everywhere.
inline double verlet_modified_energy(double kinetic, double potential, double force_term,
                                     double curvature, double h) {
  return kinetic + potential - h * h / 24.0 * force_term + h * h / 12.0 * curvature;
}

}  // namespace deli
