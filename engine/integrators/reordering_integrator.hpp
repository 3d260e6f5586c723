#pragma once

#include <functional>
#include <memory>

#include "integrators/forwarding_integrator.hpp"
#include "system/particle_order.hpp"

namespace deli {

// Any integrator with the particles put in spatial order (system/particle_order) at set-up
// and every `every` steps after, as LAMMPS' atom_modify sort: a long run mixes the
// particles, and passes over them would otherwise read their neighbours from all over
// memory. At each sort the integrator is made anew for the reordered system and resumes
// from its predecessor's saved state (reordered), the neighbour list rebuilt from the
// reordered build positions: what a restart from a checkpoint taken there does, so a run
// and its restarts stay bit for bit alike.
class ReorderingIntegrator final : public ForwardingIntegrator {
 public:
  // Puts the system and everything built on its particle indices (constraints, force field)
  // in `order` and returns an integrator for them; the previous one is gone by then.
  using Remake = std::function<std::unique_ptr<Integrator>(const ParticleOrder& order)>;
  ReorderingIntegrator(std::unique_ptr<Integrator> inner, Remake remake, std::int64_t every);

  void setup(System& system) override;
  void step(System& system, bool tally = true) override;
  // Sorts that changed the order.
  std::int64_t sorts() const { return sorts_; }

 private:
  // The order of the present neighbour list's bins: half its reach, as LAMMPS' default.
  ParticleOrder order_for(const System& system) const;

  Remake remake_;
  std::int64_t every_;
  std::int64_t sorts_ = 0;
};

}  // namespace deli
