#pragma once

#include "integrators/constrained_integrator.hpp"
#include "integrators/gvi.hpp"

namespace deli {

// The collision (event-driven hybrid) integrator the paper compares GVI with: unconstrained
// steps (Verlet or implicit midpoint) until a constraint would be crossed, the contact time
// found by root finding along the step, a reflection there (GVI's reflection, keeping H or
// Verlet's shadow H), then the rest of the step; several events per step in time order.
// Inequality constraints only (no rods or strings). Each root-finder evaluation is a
// partial step of the whole system: a baseline for small systems, not for melts.
struct CollisionOptions {
  Lagrangian base = Lagrangian::verlet;
  ReflectionEnergy energy = ReflectionEnergy::hamiltonian;
  // The contact time is bracketed to root_tolerance * h; the particle is put at the bracket's
  // feasible end, up to that far before contact.
  double root_tolerance = 1e-12;
  int max_events_per_step = 1000;
};

class CollisionIntegrator final : public ConstrainedIntegrator {
 public:
  CollisionIntegrator(const ForceField& force_field, ConstraintSet constraints, double timestep,
                      double skin, const CollisionOptions& options, const Particles& particles);

  std::string name() const override { return "collision"; }
  void step(System& system, bool tally = true) override;
  std::optional<double> shadow_energy(const System& system) const override {
    if (options_.base != Lagrangian::verlet) return std::nullopt;
    return engine_.verlet_shadow_energy(system, dt_);
  }

 private:
  // Positions after an unconstrained step of length tau from (q, p), whose force is f.
  std::vector<Vec3> free_positions(System& system, const std::vector<Vec3>& q,
                                   const std::vector<Vec3>& p, const std::vector<Vec3>& f,
                                   double tau, std::vector<Vec3>* f_mid = nullptr) const;
  // The first time in (0, tau] at which row c closes along the free step, or nothing; the
  // bracket's feasible end (counted) when limits.contact_time iterations do not narrow it.
  std::optional<double> contact_time(System& system, const Constraint& c,
                                     const std::vector<Vec3>& q, const std::vector<Vec3>& p,
                                     const std::vector<Vec3>& f, double tau);

  CollisionOptions options_;
};

}  // namespace deli
