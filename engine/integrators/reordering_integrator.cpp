#include "integrators/reordering_integrator.hpp"

namespace deli {

ReorderingIntegrator::ReorderingIntegrator(std::unique_ptr<Integrator> inner, Remake remake,
                                           std::int64_t every)
    : ForwardingIntegrator(std::move(inner)), remake_(std::move(remake)), every_(every) {
  if (every_ < 1) {
    throw InputError("sort_every = " + std::to_string(every_) +
                     ": the particles are sorted every 1 step or more (0: never, without this "
                     "integrator)");
  }
}

ParticleOrder ReorderingIntegrator::order_for(const System& system) const {
  const NeighborList& list = inner_->forces().neighbors();
  return spatial_order(system, 0.5 * (list.cutoff() + list.skin()));
}

void ReorderingIntegrator::setup(System& system) {
  const ParticleOrder order = order_for(system);
  if (!is_identity(order)) {
    inner_.reset();
    inner_ = remake_(order);
    ++sorts_;
  }
  inner_->setup(system);
}

void ReorderingIntegrator::step(System& system, bool tally) {
  inner_->step(system, tally);
  if (system.step % every_ != 0) return;
  const ParticleOrder order = order_for(system);
  if (is_identity(order)) return;
  const std::vector<double> state = inner_->state_in_order(inner_->saved_state(), order);
  const NeighborList& list = inner_->forces().neighbors();
  const std::vector<Vec3> build_positions = permuted(list.positions_at_build(), order);
  const std::int64_t builds = list.builds();
  NeighborList::Stencils stencils = inner_->engine().take_list_stencils();
  inner_.reset();
  inner_ = remake_(order);
  inner_->engine().continue_build_count(builds);
  inner_->engine().adopt_list_stencils(std::move(stencils));
  inner_->resume(system, build_positions, state);
  ++sorts_;
}

}  // namespace deli
