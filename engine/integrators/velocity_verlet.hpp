#pragma once

#include "integrators/integrator.hpp"

namespace deli {

// Velocity Verlet (LAMMPS fix nve): half kick, drift, force, half kick.
class VelocityVerlet final : public Integrator {
 public:
  VelocityVerlet(const ForceField& force_field, double skin, double timestep);

  std::string name() const override { return "verlet"; }
  double timestep() const override { return dt_; }
  void setup(System& system) override;
  ForceEngine& engine() override { return engine_; }
  void step(System& system, bool tally = true) override;
  const ForceEngine& forces() const override { return engine_; }
  std::optional<double> shadow_energy(const System& system) const override {
    return engine_.verlet_shadow_energy(system, dt_);
  }

 private:
  void half_kick(Particles& p) const;

  ForceEngine engine_;
  double dt_;
};

}  // namespace deli
