#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "constraints/constraint.hpp"
#include "integrators/force_engine.hpp"

namespace deli {

// Verlet's modified (shadow) energy less H at the engine's last evaluation,
// S - H = -h^2/24 F.M^-1.F + h^2/12 v.V''.v (ForceEngine::verlet_shadow_energy), for the
// momenta p + alpha d as a polynomial in alpha: constant + linear alpha + quadratic alpha^2.
// With d empty only the constant. None where a force term has no pairwise Hessian.
struct ShadowCorrection {
  double constant = 0;
  double linear = 0;
  double quadratic = 0;
};
// With rods (RATTLE), the same expansion on the rod manifold: the force term takes the force
// projected onto the rods' tangent space, F + f_c (M^-1-orthogonally), and the curvature
// term the Hessian of V + mu.g, g_k = (|x_i - x_j|^2 - L_k^2) / 2, with f_c = -sum_k mu_k
// grad g_k: v.V''.v + sum_k mu_k |v_i - v_j|^2 (free flight on the manifold turns with the
// rods, and the potential changes along that turn too).
struct RodShadowTerms {
  std::vector<Vec3> projected_force;  // F + f_c
  std::vector<double> multiplier;     // mu_k per rod
};
// The multipliers of `projected_force` - `force` over `rods` (least squares over the rods'
// gradients at the system's positions); none where a row is not a rod.
std::optional<RodShadowTerms> rod_shadow_terms(const System& system,
                                               const std::vector<Constraint>& rods,
                                               const std::vector<Vec3>& force,
                                               std::vector<Vec3> projected_force);
std::optional<ShadowCorrection> shadow_correction_along(
    const ForceEngine& engine, const System& system, double h, const std::vector<Vec3>& p,
    const std::vector<Vec3>& d, const std::vector<Constraint>* rods = nullptr,
    const RodShadowTerms* rod_terms = nullptr);
// The rod terms at the engine's last evaluation: its force projected by `project` (as
// shadow_correction_on_rods does) and the multipliers; with no force, the force itself and
// zero multipliers. None where a row is not a rod.
std::optional<RodShadowTerms> projected_rod_terms(
    const ForceEngine& engine, const System& system, const std::vector<Constraint>& rods,
    const std::function<void(std::vector<Vec3>&)>& project);
// Verlet's (RATTLE's) modified energy S with the rod terms at the engine's last evaluation
// (energies tallied) and the system's velocities: the force projected M^-1-orthogonally onto
// the rods' tangent space by a direct solve, (G M^-1 G^T) mu = G M^-1 F. The thermo's
// shadow_energy with rods. None where a row is not a rod or S has no closed form.
std::optional<double> verlet_shadow_energy_on_rods(const ForceEngine& engine, const System& system,
                                                   double h, const std::vector<Constraint>& rods);
// shadow_correction_along with the rod terms of `rods` when there are any; `project` projects
// a force onto the rods' tangent space at the system's positions, as momenta.
std::optional<ShadowCorrection> shadow_correction_on_rods(
    const ForceEngine& engine, const System& system, double h, const std::vector<Vec3>& p,
    const std::vector<Vec3>& d, const std::vector<Constraint>& rods,
    const std::function<void(std::vector<Vec3>&)>& project);

}  // namespace deli
