#pragma once

#include <memory>
#include <string>
#include <vector>

#include "constraints/constraint.hpp"
#include "crosscheck/evaluation.hpp"
#include "force_field_spec.hpp"
#include "system/system.hpp"

namespace deli {

// The same model in OpenMM, in this process: sigma = 1 nm, epsilon = 1 kJ/mol, m = 1 amu,
// so tau = 1 ps and every number carries over unchanged. Pairs go through a
// CustomNonbondedForce with per-type-pair tables (explicit and mixed coefficients, per
// pair cutoffs, optional shift; no switching, no long-range correction), excluded exactly
// where deli excludes them; bonds, angles and dihedrals through a CustomBondForce,
// CustomAngleForce and CustomTorsionForce per style with the style's registered expression.
class OpenMMBridge {
 public:
  enum class Platform { reference, cpu };
  // Throws UnsupportedModel for what OpenMM cannot express (mixed periodicity).
  // `rods` (optional) become OpenMM constraints, held to `constraint_tolerance` (relative):
  // the RATTLE reference for GVI with rods only.
  OpenMMBridge(const System& system, const ForceFieldSpec& spec, Platform platform,
               const std::vector<Constraint>& rods = {}, double constraint_tolerance = 1e-12);
  ~OpenMMBridge();

  std::string name() const;
  EngineEvaluation evaluate(const std::vector<Vec3>& position);
  // Positions after `steps` of NVE from (x, v) with VerletIntegrator. OpenMM's integrator
  // is leapfrog: it is given v(-dt/2) = v - dt/2 F/m, after which its positions are those
  // of velocity Verlet.
  std::vector<Vec3> run_nve(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity,
                            int steps, double dt);
  // Potential and kinetic energy series of LangevinMiddleIntegrator (Zhang et al., J. Phys.
  // Chem. A 123, 6056, 2019: a leapfrog form of BAOAB) from (x, v), rods held as
  // constraints. OpenMM takes the bath in kelvin: kT = 1 kJ/mol = epsilon at T = 1 / (k_B
  // N_A in kJ/mol/K), and friction 1 / damping per ps. Its kinetic energy is that of the
  // velocities it holds, half a step from the positions (after the O part of the step).
  EnergySeries run_langevin(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity,
                            const LangevinRun& run);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace deli
