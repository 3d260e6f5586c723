#include "integrators/force_engine.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/phase_timer.hpp"
#include "forces/special_bonds.hpp"
#include "system/finite_state.hpp"

namespace deli {

ForceEngine::ForceEngine(const ForceField& force_field, double skin, double minimum_cutoff)
    : force_field_(force_field),
      neighbors_(std::max(force_field.neighbor_cutoff(), minimum_cutoff), skin) {
  neighbors_.set_cell_order(force_field.cell_order);
}

bool ForceEngine::ensure_neighbors(System& system, bool force) {
  return ensure_neighbors(system, force, nullptr);
}

bool ForceEngine::ensure_neighbors(System& system, bool force, const RangePass* after_wrap) {
  const TimedPhase timed(Phase::neighbor);
  Particles& p = system.particles;
  if (!force && !neighbors_.needs_rebuild(p.position)) return false;
  // Rebuilds are rare, and every non-finite position triggers one (needs_rebuild): the
  // one place a blown-up run is caught on the step it happens. Each chunk checks its atoms
  // and wraps them (a wrap is a few divisions' worth: substantial items, split as the pair
  // loop, not in chunks of cheap_chunk_minimum()) in one pass; the scans that name a bad atom run
  // only if a chunk found one. Checked first on one thread and then wrapped, the rigid melt's 4000
  // beads were read three times a build while the other thread waited. The pass runs in the
  // list build's first job, each chunk checked and wrapped just before the build copies it (in
  // a job of its own it cost a job and a read of the positions more a build). Nothing reads a
  // list of zero reach: keep the first one, unwrapped.
  const bool keep_list = neighbors_.cutoff() <= 0 && neighbors_.builds() > 0;
  bool usable = true;
  if (keep_list) {
    const int chunks = chunks_for(p.size());
    std::vector<char> chunk_usable(static_cast<std::size_t>(chunks), 1);
    for_each_chunk(p.size(), chunks, [&](int c, std::size_t begin, std::size_t end) {
      chunk_usable[static_cast<std::size_t>(c)] = atoms_usable(p, system.box, begin, end);
    });
    usable = std::find(chunk_usable.begin(), chunk_usable.end(), 0) == chunk_usable.end();
  } else {
    if (neighbors_.builds() == 0) {
      const SpecialPairs special = find_special_pairs(system.topology, p.size());
      neighbors_.set_exclusions(special_exclusions(special, force_field_.special_lj));
    }
    const NeighborList::ChunkCheck check_and_wrap = [&](std::size_t begin, std::size_t end) {
      if (!atoms_usable(p, system.box, begin, end)) return false;
      for (std::size_t i = begin; i < end; ++i) system.box.wrap(p.position[i], p.image[i]);
      if (after_wrap) (*after_wrap)(begin, end);
      return true;
    };
    usable = neighbors_.build(p.position, system.box, &check_and_wrap);
  }
  if (!usable) {
    if (auto bad = first_non_finite_atom(p)) {
      throw SimulationError("step " + std::to_string(system.step) + ": " + *bad +
                            " is not finite: the run blew up (a timestep too large, overlapping "
                            "atoms or extreme force-field numbers); outputs up to the last "
                            "sample are kept");
    }
    if (auto away = first_runaway_atom(p, system.box)) {
      throw SimulationError("step " + std::to_string(system.step) + ": " + *away +
                            " ran away (far beyond the box): the run blew up (a timestep too "
                            "large, overlapping atoms or extreme force-field numbers); outputs "
                            "up to the last sample are kept");
    }
    throw std::logic_error("atoms_usable found an atom that neither scan names");
  }
  return !keep_list;
}

void ForceEngine::restore_neighbors(System& system, const std::vector<Vec3>& build_positions) {
  const SpecialPairs special = find_special_pairs(system.topology, system.particles.size());
  neighbors_.set_exclusions(special_exclusions(special, force_field_.special_lj));
  neighbors_.build(build_positions, system.box);
}

const ForceEvaluation& ForceEngine::compute(System& system, bool tally) {
  return compute(system, tally, false);
}

const ForceEvaluation& ForceEngine::compute(System& system, bool tally, bool listed) {
  if (!listed) ensure_neighbors(system);
  const bool no_terms = force_field_.terms().empty();
  if (no_terms && force_zero_ && force_.size() == system.particles.size()) {
    last_ = ForceEvaluation{};  // what compute() returns without terms
    last_.tallied = tally;
    return last_;
  }
  last_ = force_field_.compute(system, neighbors_, force_, tally);
  force_zero_ = no_terms;
  return last_;
}

void ForceEngine::forces_at(System& system, const std::vector<Vec3>& x,
                            std::vector<Vec3>& force) const {
  std::vector<Vec3>& position = system.particles.position;
  std::vector<Vec3> kept = x;
  position.swap(kept);
  force_field_.compute(system, neighbors_, force, false);
  position.swap(kept);
}

std::optional<double> ForceEngine::verlet_shadow_energy(const System& system, double h) const {
  if (!last_.tallied) return std::nullopt;
  const Particles& p = system.particles;
  double curvature = 0;
  if (!force_field_.pair_curvature(system, neighbors_, p.velocity, curvature)) return std::nullopt;
  const double kinetic = ordered_sum<double>(
      p.size(), [&](std::size_t i) { return 0.5 * p.mass[i] * norm2(p.velocity[i]); });
  const double force_term =
      ordered_sum<double>(p.size(), [&](std::size_t i) { return norm2(force_[i]) / p.mass[i]; });
  return verlet_modified_energy(kinetic, last_.potential, force_term, curvature, h);
}

std::vector<std::array<std::int32_t, 2>> special_exclusions(const SpecialPairs& special,
                                                            const std::array<double, 3>& factors) {
  std::vector<std::array<std::int32_t, 2>> excluded;
  for (const ExcludedSpecialPair& p : excluded_special_pairs(special, factors)) {
    excluded.push_back({p.i, p.j});
  }
  return excluded;
}

}  // namespace deli
