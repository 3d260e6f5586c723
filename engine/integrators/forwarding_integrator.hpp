#pragma once

#include <memory>
#include <utility>

#include "integrators/integrator.hpp"

namespace deli {

// An integrator around another that passes every call on to it: the base of the wrappers
// (a heat bath, the spatial sort), which override only what they change.
class ForwardingIntegrator : public Integrator {
 public:
  explicit ForwardingIntegrator(std::unique_ptr<Integrator> inner) : inner_(std::move(inner)) {}

  std::string name() const override { return inner_->name(); }
  double timestep() const override { return inner_->timestep(); }
  void setup(System& system) override { inner_->setup(system); }
  ForceEngine& engine() override { return inner_->engine(); }
  const ForceEngine& forces() const override { return inner_->forces(); }
  void step(System& system, bool tally = true) override { inner_->step(system, tally); }
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
                                     const std::vector<std::int32_t>& order) const override {
    return inner_->state_in_order(state, order);
  }
  void restore_state(const std::vector<double>& state, const System& system) override {
    inner_->restore_state(state, system);
  }

 protected:
  std::unique_ptr<Integrator> inner_;
};

}  // namespace deli
