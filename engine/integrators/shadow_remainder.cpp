#include "integrators/shadow_remainder.hpp"

#include "integrators/shadow_correction.hpp"

namespace deli {

std::optional<double> moving_shadow_energy(const ForceEngine& engine, const System& system,
                                           const std::vector<Vec3>& p,
                                           const std::vector<char>& moving, double h,
                                           const RodStages* rods) {
  const Particles& P = system.particles;
  std::optional<RodShadowTerms> rod_terms;
  if (rods) {
    rod_terms = projected_rod_terms(engine, system, rods->rods, [&](std::vector<Vec3>& force) {
      rods->project(P.position, force);
    });
    if (!rod_terms) return std::nullopt;
  }
  const std::vector<Vec3>& force = rod_terms ? rod_terms->projected_force : engine.force();
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
  if (rod_terms) {
    // Free flight on the manifold turns with the rods (shadow_correction.hpp).
    for (std::size_t k = 0; k < rods->rods.size(); ++k) {
      const Constraint& c = rods->rods[k];
      if (!moving[c.i]) continue;
      curvature += rod_terms->multiplier[k] * norm2(velocity[c.i] - velocity[c.j]);
    }
  }
  return verlet_modified_energy(kinetic, engine.last().potential, force_term, curvature, h);
}

std::optional<double> shadow_remainder(ForceEngine& engine, const System& system,
                                       const std::vector<Vec3>& x, const std::vector<Vec3>& p,
                                       const std::vector<char>& moving, double h, double step,
                                       int steps, const RodStages* rods) {
  const Particles& P = system.particles;
  System virtual_system = system;
  virtual_system.particles.position = x;
  engine.compute(virtual_system, true);
  const std::optional<double> at_state =
      moving_shadow_energy(engine, virtual_system, p, moving, h, rods);
  if (!at_state) return std::nullopt;
  std::vector<Vec3> momenta = p;
  std::vector<Vec3>& position = virtual_system.particles.position;
  std::vector<Vec3> kicked, to;
  double sum = 0;
  int count = 0;
  for (int s = 1; s <= steps; ++s) {
    if (rods) {
      // RATTLE: the drift held on the rods; the particles that hold still keep their place.
      kicked.assign(P.size(), Vec3{});
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (moving[i]) kicked[i] = momenta[i] + engine.force()[i] * (0.5 * step);
      }
      rods->drift(position, kicked, step, to);
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (!moving[i]) continue;
        momenta[i] = kicked[i];
        position[i] = to[i];
      }
    } else {
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (!moving[i]) continue;
        momenta[i] += engine.force()[i] * (0.5 * step);
        position[i] += momenta[i] * (step / P.mass[i]);
      }
    }
    const bool averaged = 2 * s > steps;
    engine.compute(virtual_system, averaged);
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (moving[i]) momenta[i] += engine.force()[i] * (0.5 * step);
    }
    if (rods) {
      kicked.assign(P.size(), Vec3{});
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (moving[i]) kicked[i] = momenta[i];
      }
      rods->project(position, kicked);
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (moving[i]) momenta[i] = kicked[i];
      }
    }
    if (!averaged) continue;
    const std::optional<double> shadow =
        moving_shadow_energy(engine, virtual_system, momenta, moving, h, rods);
    if (!shadow) return std::nullopt;
    sum += *shadow;
    ++count;
  }
  return sum / count - *at_state;
}

}  // namespace deli
