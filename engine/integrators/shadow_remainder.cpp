#include "integrators/shadow_remainder.hpp"

namespace deli {

std::optional<double> moving_shadow_energy(const ForceEngine& engine, const System& system,
                                           const std::vector<Vec3>& p,
                                           const std::vector<char>& moving, double h) {
  const Particles& P = system.particles;
  const std::vector<Vec3>& force = engine.force();
  std::vector<Vec3> velocity(P.size());
  double kinetic = 0, force_term = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (!moving[i]) continue;
    velocity[i] = p[i] * (1.0 / P.mass[i]);
    kinetic += 0.5 * norm2(p[i]) / P.mass[i];
    force_term += norm2(force[i]) / P.mass[i];
  }
  double curvature = 0;
  if (!engine.force_field().pair_curvature(system, engine.neighbors(), velocity, curvature)) {
    return std::nullopt;
  }
  return verlet_modified_energy(kinetic, engine.last().potential, force_term, curvature, h);
}

std::optional<double> shadow_remainder(ForceEngine& engine, const System& system,
                                       const std::vector<Vec3>& x, const std::vector<Vec3>& p,
                                       const std::vector<char>& moving, double h, double step,
                                       int steps) {
  const Particles& P = system.particles;
  System virtual_system = system;
  virtual_system.particles.position = x;
  engine.compute(virtual_system, true);
  const std::optional<double> at_state = moving_shadow_energy(engine, virtual_system, p, moving, h);
  if (!at_state) return std::nullopt;
  std::vector<Vec3> momenta = p;
  std::vector<Vec3>& position = virtual_system.particles.position;
  double sum = 0;
  int count = 0;
  for (int s = 1; s <= steps; ++s) {
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (!moving[i]) continue;
      momenta[i] += engine.force()[i] * (0.5 * step);
      position[i] += momenta[i] * (step / P.mass[i]);
    }
    const bool averaged = 2 * s > steps;
    engine.compute(virtual_system, averaged);
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (moving[i]) momenta[i] += engine.force()[i] * (0.5 * step);
    }
    if (!averaged) continue;
    const std::optional<double> shadow =
        moving_shadow_energy(engine, virtual_system, momenta, moving, h);
    if (!shadow) return std::nullopt;
    sum += *shadow;
    ++count;
  }
  return sum / count - *at_state;
}

}  // namespace deli
