#include "simulation/thermo.hpp"

#include <stdexcept>

#include "core/parallel.hpp"

namespace deli {

double kinetic_energy(const Particles& p) {
  const double twice = ordered_sum<double>(
      p.size(), [&](std::size_t i) { return p.mass[i] * norm2(p.velocity[i]); });
  return 0.5 * twice;
}

Vec3 total_momentum(const Particles& p) {
  return ordered_sum<Vec3>(p.size(), [&](std::size_t i) { return p.velocity[i] * p.mass[i]; });
}

ThermoSample measure_thermo(const System& system, const ForceEvaluation& evaluation,
                            const DegreesOfFreedom& dof) {
  if (!evaluation.tallied)
    throw std::logic_error("thermo asked of a force evaluation without energies");
  ThermoSample s;
  s.step = system.step;
  s.time = system.time;
  s.kinetic = kinetic_energy(system.particles);
  s.potential = evaluation.potential;
  s.total = s.kinetic + s.potential;
  s.degrees_of_freedom = dof.count();
  s.temperature = s.degrees_of_freedom > 0 ? 2.0 * s.kinetic / s.degrees_of_freedom : 0.0;
  s.pressure = (2.0 * s.kinetic + evaluation.virial.trace()) / (3.0 * system.box.volume());
  s.momentum = total_momentum(system.particles);
  const Box& box = system.box;
  if (!box.periodic(0) && !box.periodic(1) && !box.periodic(2)) {
    const Particles& p = system.particles;
    s.angular_momentum = ordered_sum<Vec3>(
        p.size(), [&](std::size_t i) { return cross(p.position[i], p.velocity[i] * p.mass[i]); });
  }
  s.term_names = evaluation.names;
  s.term_energies = evaluation.energies;
  return s;
}

}  // namespace deli
