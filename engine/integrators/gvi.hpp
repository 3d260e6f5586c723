#pragma once

#include "integrators/constrained_integrator.hpp"

namespace deli {

// The generalized variational integrator (Kaufman & Pai, Algorithm 1) with the Verlet
// discrete Lagrangian: forward predictor, extended active set, energy-preserving
// reflection, smooth set, position update (a complementarity problem per cluster),
// momentum update. With rods only it is RATTLE; with no constraints, velocity Verlet.
// Choices the paper leaves open are documented in the README ("GVI").
//
// Feasibility guard (the paper lets a step end overlapped, e.g. a slow particle pulled into
// a wall whose predicted overlap it does not approach fast enough to reflect): rows that
// would end the step overlapped join the position update's complementarity set, which
// lands them at contact; then `reflect` reflects the momenta still approaching them at the
// end of the step (elastic), `inelastic` projects that approach away, `none` keeps the
// literal algorithm (overlaps are only counted).
// `restore` is `reflect` followed by an impulse along the landed rows' normals that brings
// the energy H back to its value at the start of the step (the landing moved the particle
// and changed its potential energy); where the normal motion cannot supply the difference
// the normal velocity is zeroed and the event counted as a deficit.
enum class Feasibility { restore, reflect, inelastic, none };
enum class Lagrangian { verlet, midpoint };

struct GviOptions {
  Lagrangian lagrangian = Lagrangian::verlet;
  // false: the Discrete-Smooth Integrator (no reflections; every row of the extended
  // active set enters the position update's complementarity problem).
  bool reflections = true;
  // Predict with the equality rows solved (else the unconstrained step, as the paper).
  bool constrained_predictor = false;
  double timestep = 0.005;
  double skin = 0.3;
  ReflectionOperator reflection = ReflectionOperator::generalized;
  ReflectionEnergy energy = ReflectionEnergy::hamiltonian;
  Feasibility feasibility = Feasibility::restore;
};

class Gvi final : public ConstrainedIntegrator {
 public:
  Gvi(const ForceField& force_field, ConstraintSet constraints, const GviOptions& options,
      const Particles& particles);

  std::string name() const override { return reflections_ ? "gvi" : "dsi"; }
  void step(System& system, bool tally = true) override;
  std::optional<double> shadow_energy(const System& system) const override {
    if (lagrangian_ != Lagrangian::verlet) return std::nullopt;
    return engine_.verlet_shadow_energy(system, dt_);
  }

 private:
  void restore_energy(System& system, const std::vector<Constraint>& landed, double target,
                      std::vector<Vec3>& p);

  Feasibility feasibility_;
  Lagrangian lagrangian_;
  bool reflections_;
  bool constrained_predictor_;
};

}  // namespace deli
