#pragma once

#include <functional>
#include <memory>

#include "integrators/integrator.hpp"
#include "system/particle_order.hpp"

namespace deli {

// Any integrator with the particles put in spatial order (system/particle_order) at set-up
// and every `every` steps after, as LAMMPS' atom_modify sort: a long run mixes the
// particles, and passes over them would otherwise read their neighbours from all over
// memory. At each sort the integrator is made anew for the reordered system and resumes
// from its predecessor's saved state (reordered), the neighbour list rebuilt from the
// reordered build positions: what a restart from a checkpoint taken there does, so a run
// and its restarts stay bit for bit alike.
class ReorderingIntegrator final : public Integrator {
 public:
  // Puts the system and everything built on its particle indices (constraints, force field)
  // in `order` and returns an integrator for them; the previous one is gone by then.
  using Remake = std::function<std::unique_ptr<Integrator>(const ParticleOrder& order)>;
  ReorderingIntegrator(std::unique_ptr<Integrator> inner, Remake remake, std::int64_t every);

  std::string name() const override { return inner_->name(); }
  double timestep() const override { return inner_->timestep(); }
  void setup(System& system) override;
  ForceEngine& engine() override { return inner_->engine(); }
  const ForceEngine& forces() const override { return inner_->forces(); }
  void step(System& system, bool tally = true) override;
  std::vector<std::pair<std::string, double>> take_statistics(Sampler sampler, bool keep) override {
    return inner_->take_statistics(sampler, keep);
  }
  double take_constraint_virial(Sampler sampler, bool keep) override {
    return inner_->take_constraint_virial(sampler, keep);
  }
  std::optional<double> shadow_energy(const System& system) const override {
    return inner_->shadow_energy(system);
  }
  void project_velocities(System& system) override { inner_->project_velocities(system); }
  std::optional<double> bath_energy() const override { return inner_->bath_energy(); }
  std::vector<double> saved_state() const override { return inner_->saved_state(); }
  std::vector<double> state_in_order(const std::vector<double>& state,
                                     const ParticleOrder& order) const override {
    return inner_->state_in_order(state, order);
  }
  void restore_state(const std::vector<double>& state, const System& system) override {
    inner_->restore_state(state, system);
  }

  // Sorts that changed the order.
  std::int64_t sorts() const { return sorts_; }

 private:
  // The order of the present neighbour list's bins: half its reach, as LAMMPS' default.
  ParticleOrder order_for(const System& system) const;

  std::unique_ptr<Integrator> inner_;
  Remake remake_;
  std::int64_t every_;
  std::int64_t sorts_ = 0;
};

}  // namespace deli
