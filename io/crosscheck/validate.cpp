#include "crosscheck/validate.hpp"

#include "integrators/velocity_verlet.hpp"
#include "lammps/lammps_bridge.hpp"
#include "openmm/openmm_bridge.hpp"

namespace deli {

bool ValidationReport::passed() const {
  for (const Check& c : checks) {
    if (!c.within()) return false;
  }
  return true;
}

const Check* ValidationReport::worst() const {
  const Check* worst = nullptr;
  for (const Check& c : checks) {
    if (!worst || c.difference / c.tolerance > worst->difference / worst->tolerance) worst = &c;
  }
  return worst;
}

namespace {

EngineEvaluation evaluate_deli(const RunInput& input, System& system) {
  ForceEngine engine(*input.force_field, input.skin);
  const ForceEvaluation& f = engine.compute(system);
  EngineEvaluation e;
  e.engine = "deli";
  e.term_names = f.names;
  e.term_energies = f.energies;
  e.potential = f.potential;
  e.force = engine.force();
  e.virial = f.virial.trace();
  return e;
}

std::vector<Vec3> deli_trajectory(const RunInput& input, System system, int steps) {
  VelocityVerlet verlet(*input.force_field, input.skin, input.timestep);
  verlet.setup(system);
  for (int n = 0; n < steps; ++n) verlet.step(system, false);
  std::vector<Vec3> unwrapped;
  for (std::size_t i = 0; i < system.particles.size(); ++i) {
    unwrapped.push_back(
        system.box.unwrapped(system.particles.position[i], system.particles.image[i]));
  }
  return unwrapped;
}

std::vector<Vec3> unwrapped_start(const System& system) {
  std::vector<Vec3> x;
  for (std::size_t i = 0; i < system.particles.size(); ++i) {
    x.push_back(system.box.unwrapped(system.particles.position[i], system.particles.image[i]));
  }
  return x;
}

}  // namespace

ValidationReport validate(const RunInput& input, const ValidateOptions& options) {
  if (input.force_field_spec.gravity || !input.force_field_spec.radial.empty()) {
    throw UnsupportedModel(
        "deli validate compares force fields of pair, bond and angle terms; "
        "this input has an external field (gravity)");
  }
  if (!input.constraints.empty()) {
    throw UnsupportedModel(
        "deli validate compares unconstrained force fields; this input has "
        "[constraints] (remove them to validate its force field)");
  }
  ValidationReport report;
  System start = input.system;
  const std::vector<std::int64_t>& ids = start.particles.id;
  report.deli = evaluate_deli(input, start);
  std::vector<Vec3> deli_positions;
  if (options.trajectory_steps > 0) {
    deli_positions = deli_trajectory(input, input.system, options.trajectory_steps);
  }

  if (options.openmm) {
    try {
      OpenMMBridge openmm(
          input.system, input.force_field_spec,
          options.openmm_cpu ? OpenMMBridge::Platform::cpu : OpenMMBridge::Platform::reference);
      const Tolerances tol =
          options.openmm_cpu ? single_precision_tolerances() : double_precision_tolerances(true);
      const std::vector<Vec3> x0 = unwrapped_start(input.system);
      report.others.push_back(openmm.evaluate(x0));
      const auto checks = compare_evaluations(report.deli, report.others.back(), tol, ids);
      report.checks.insert(report.checks.end(), checks.begin(), checks.end());
      if (options.trajectory_steps > 0) {
        const auto x = openmm.run_nve(x0, input.system.particles.velocity, options.trajectory_steps,
                                      input.timestep);
        report.checks.push_back(compare_positions(openmm.name(), deli_positions, x, tol, ids,
                                                  options.trajectory_steps));
      }
    } catch (const UnsupportedModel& e) {
      report.skipped.push_back(std::string("OpenMM: ") + e.what());
    }
  }
  if (options.lammps) {
    LammpsBridge lammps(input.system, input.force_field_spec, input.skin);
    const Tolerances tol = double_precision_tolerances(false);
    report.others.push_back(lammps.evaluate());
    const auto checks = compare_evaluations(report.deli, report.others.back(), tol, ids);
    report.checks.insert(report.checks.end(), checks.begin(), checks.end());
    if (options.trajectory_steps > 0) {
      const auto x = lammps.run_nve(options.trajectory_steps, input.timestep);
      report.checks.push_back(
          compare_positions(lammps.name(), deli_positions, x, tol, ids, options.trajectory_steps));
    }
  }
  return report;
}

}  // namespace deli
