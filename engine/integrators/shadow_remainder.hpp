#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "constraints/constraint.hpp"
#include "integrators/force_engine.hpp"

namespace deli {

// RATTLE's two constraint stages on the rods, for virtual steps of a system with rods.
// `drift`: from positions x with half-kicked momenta p over time `step`, the end positions on
// the rods into `to`, the rods' impulse added to p. `project`: momenta (or a force) p
// projected onto the rods' tangent space at x.
struct RodStages {
  const std::vector<Constraint>& rods;
  std::function<void(const std::vector<Vec3>& x, std::vector<Vec3>& p, double step,
                     std::vector<Vec3>& to)>
      drift;
  std::function<void(const std::vector<Vec3>& x, std::vector<Vec3>& p)> project;
};

// Verlet's modified energy beyond its h^2 terms (README, "Contact treatment"). Verlet keeps a
// modified energy S~ = S + O(h^4) (S = H - h^2/24 F.M^-1.F + h^2/12 v.V''.v); on LJ's steep
// wall at h omega about 0.5 the rest, R = S~ - S, is as large as the energy lost at a contact
// when a contact step gives back S alone. R falls off with the steep force, so it is read
// from Verlet's own steps: the mean of S over the last half of `steps` virtual Verlet steps
// taken away from the contact (time step +h after it, -h before it), less S at the state.
// Only the particles `moving` move, the others hold still as a fixed field (so that other
// pairs' motion does not enter); S is taken over the moving particles (their kinetic energy,
// their force term and the curvature with the others at rest, and all of V). Soft forces only:
// the virtual steps have no hard rows. With `rods` the virtual steps are RATTLE's (positions
// held on the rods, momenta projected), `moving` must hold whole rod clusters, and S has the
// rod terms (shadow_correction.hpp: the projected force, mu_k |v_i - v_j|^2). The engine's
// state is left at the last virtual configuration (compute again at the real one). None
// where S has no closed form (a force term without pairwise Hessian).
std::optional<double> shadow_remainder(ForceEngine& engine, const System& system,
                                       const std::vector<Vec3>& x, const std::vector<Vec3>& p,
                                       const std::vector<char>& moving, double h, double step,
                                       int steps, const RodStages* rods = nullptr);

// S of the particles `moving` at the engine's last evaluation (energies tallied), momenta p;
// with `rods`, the rod terms of the rods between moving particles.
std::optional<double> moving_shadow_energy(const ForceEngine& engine, const System& system,
                                           const std::vector<Vec3>& p,
                                           const std::vector<char>& moving, double h,
                                           const RodStages* rods = nullptr);

}  // namespace deli
