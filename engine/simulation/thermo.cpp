#include "simulation/thermo.hpp"

#include <stdexcept>

namespace deli {

double kinetic_energy(const Particles& p) {
  double twice = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) twice += p.mass[i] * norm2(p.velocity[i]);
  return 0.5 * twice;
}

Vec3 total_momentum(const Particles& p) {
  Vec3 m;
  for (std::size_t i = 0; i < p.size(); ++i) m += p.velocity[i] * p.mass[i];
  return m;
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
    Vec3 l;
    const Particles& p = system.particles;
    for (std::size_t i = 0; i < p.size(); ++i) l += cross(p.position[i], p.velocity[i] * p.mass[i]);
    s.angular_momentum = l;
  }
  s.term_names = evaluation.names;
  s.term_energies = evaluation.energies;
  return s;
}

}  // namespace deli
