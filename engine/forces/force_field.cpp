#include "forces/force_field.hpp"

#include <algorithm>

#include "core/parallel.hpp"
#include "core/phase_timer.hpp"
#include "system/system.hpp"

namespace deli {

namespace {
// Zeroed by chunks (32000 atoms' forces are 768 kB: a serial memset held up the threads).
void zero_forces(std::vector<Vec3>& force) {
  parallel_for(force.size(), [&](std::size_t i) { force[i] = Vec3{}; });
}
}  // namespace

void ForceField::add(std::unique_ptr<ForceTerm> term) {
  terms_.push_back(std::move(term));
}

double ForceField::neighbor_cutoff() const {
  double cutoff = 0.0;
  for (const auto& term : terms_) cutoff = std::max(cutoff, term->neighbor_cutoff());
  return cutoff;
}

bool ForceField::pair_hessians(const System& system, const NeighborList& neighbors,
                               const std::vector<char>& mask, std::vector<PairHessian>& out) const {
  for (const auto& term : terms_) {
    if (!term->pair_hessians(system, neighbors, mask, out)) return false;
  }
  return true;
}

bool ForceField::pair_hessian_pieces(const System& system, const NeighborList& neighbors,
                                     const std::vector<char>& mask, PairHessianPieces& out) const {
  for (const auto& term : terms_) {
    if (!term->pair_hessian_pieces(system, neighbors, mask, out)) return false;
  }
  return true;
}

bool ForceField::pair_curvature(const System& system, const NeighborList& neighbors,
                                const std::vector<Vec3>& velocity, double& sum) const {
  for (const auto& term : terms_) {
    if (!term->pair_curvature(system, neighbors, velocity, sum)) return false;
  }
  return true;
}

double ForceTerm::compute_overwriting(const System& system, const NeighborList& neighbors,
                                      std::vector<Vec3>& force, SymTensor& virial,
                                      bool tally) const {
  zero_forces(force);
  return compute(system, neighbors, force, virial, tally);
}

bool ForceTerm::pair_curvature(const System& system, const NeighborList& neighbors,
                               const std::vector<Vec3>& velocity, double& sum) const {
  std::vector<PairHessian> blocks;
  if (!pair_hessians(system, neighbors, {}, blocks)) return false;
  for (const PairHessian& b : blocks) sum += block_curvature(b.block, velocity[b.a], velocity[b.b]);
  return true;
}

ForceEvaluation ForceField::compute(const System& system, const NeighborList& neighbors,
                                    std::vector<Vec3>& force, bool tally) const {
  force.resize(system.particles.size());
  if (terms_.empty()) zero_forces(force);
  ForceEvaluation result;
  result.tallied = tally;
  for (const auto& term : terms_) {
    // Terms that read the neighbour list are the pair forces; the rest are bonded terms.
    const TimedPhase timed(term->neighbor_cutoff() > 0 ? Phase::pair : Phase::bonded);
    const double e = &term == &terms_.front()
                         ? term->compute_overwriting(system, neighbors, force, result.virial, tally)
                         : term->compute(system, neighbors, force, result.virial, tally);
    // Terms of one name (gravity and the radial fields are all "external") are one term:
    // the thermo CSV and the H5MD observables have one column or series per name.
    const std::string name = term->name();
    const auto same = std::find(result.names.begin(), result.names.end(), name);
    if (same == result.names.end()) {
      result.names.push_back(name);
      result.energies.push_back(e);
    } else {
      result.energies[static_cast<std::size_t>(same - result.names.begin())] += e;
    }
    result.potential += e;
  }
  return result;
}

}  // namespace deli
