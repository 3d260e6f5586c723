#pragma once

#include <memory>

#include "integrators/forwarding_integrator.hpp"
#include "thermostats/thermostat.hpp"

namespace deli {

// Any integrator at constant temperature: the bath acts for h/2 before and h/2 after each
// step (with velocity Verlet, the OBABO splitting of Bussi and Parrinello, PRE 75, 056707,
// 2007), its momenta then projected onto the rods' cotangent space (rods stay exact, their
// impulses stay out of the bath: no virial, no bath energy). Contacts and walls act as
// always, through the integrator's step. The energy the bath puts in is accumulated, so
// that total energy minus it is conserved up to the integrator's error.
class ThermostattedIntegrator final : public ForwardingIntegrator {
 public:
  ThermostattedIntegrator(std::unique_ptr<Integrator> inner, const ThermostatSettings& settings,
                          const DegreesOfFreedom& dof);

  std::string name() const override;
  void step(System& system, bool tally = true) override;
  std::optional<double> bath_energy() const override { return bath_energy_; }
  // The inner integrator's state, then the thermostat's: a tag, seed, kind, bath energy.
  std::vector<double> saved_state() const override;
  std::vector<double> state_in_order(const std::vector<double>& state,
                                     const std::vector<std::int32_t>& order) const override;
  void restore_state(const std::vector<double>& state, const System& system) override;

 private:
  void act(System& system, std::int64_t step, int half);

  ThermostatSettings settings_;
  DegreesOfFreedom dof_;
  std::unique_ptr<Thermostat> thermostat_;
  double bath_energy_ = 0.0;
};

}  // namespace deli
