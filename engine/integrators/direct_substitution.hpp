#pragma once

#include "integrators/constrained_integrator.hpp"

namespace deli {

// Direct substitution (the paper's Appendix B): the constraint force -dI_A is treated as one
// more force of an unconstrained method, so each step is the constrained minimisation
//   q1 = argmin { e(q0, q, h) : g((1 - alpha) q0 + alpha q) >= 0, f(...) = 0 },
// whose KKT conditions put impulses along the gradients at the constraint point
// y = (1 - alpha) q0 + alpha q1 and land y exactly on the boundary. Baselines for the
// paper's comparisons; they share GVI's cluster solves.
//  - midpoint: implicit midpoint, constraint at the midpoint (alpha = 1/2) or the endpoint
//    (alpha = 1); p1 = 2/h M (q1 - q0) - p0.
//  - newmark: the Newmark family (beta > 0, gamma), the constraint force weighted like the
//    other forces between t and t+1 (its value at t is the previous step's).
//  - kane_imex: Kane's IMEX Newmark, the constraint force fully implicit (beta = 1/2,
//    gamma = 1 for it alone), the smooth forces with (beta, gamma).
enum class DirectScheme { midpoint, newmark, kane_imex };

struct DirectOptions {
  DirectScheme scheme = DirectScheme::midpoint;
  double alpha = 1.0;  // midpoint scheme: 0.5 midpoint-constrained, 1 endpoint-constrained
  double beta = 0.25, gamma = 0.5;
};

class DirectSubstitution final : public ConstrainedIntegrator {
 public:
  DirectSubstitution(const ForceField& force_field, ConstraintSet constraints, double timestep,
                     double skin, const DirectOptions& options, const Particles& particles);

  std::string name() const override { return "direct"; }
  void step(System& system, bool tally = true) override;
  std::vector<double> saved_state() const override;
  std::vector<double> state_in_order(const std::vector<double>& state,
                                     const std::vector<std::int32_t>& order) const override;
  void restore_state(const std::vector<double>& state, const System& system) override;

 private:
  // Lands the constraint point: y = y0 + M^-1 J with every held row satisfied at y and the
  // impulses along the gradients at y (fixed point on the gradient point). Rows of the
  // candidates found overlapping at y join `held`. Returns y; J in `impulse` (solver units).
  std::vector<Vec3> land(System& system, const std::vector<Vec3>& q, const std::vector<Vec3>& y0,
                         const std::vector<Constraint>& candidates, std::vector<Constraint>& held,
                         std::vector<Vec3>& impulse, double& virial);

  DirectOptions options_;
  std::vector<Vec3> constraint_force_;  // Newmark: the constraint force at the current step
};

}  // namespace deli
