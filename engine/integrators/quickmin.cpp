#include "integrators/quickmin.hpp"

#include <algorithm>
#include <cmath>

namespace deli {

namespace {
double largest_component(const std::vector<Vec3>& f) {
  double m = 0.0;
  for (const Vec3& v : f) m = std::max({m, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  return m;
}
}  // namespace

MinimizeResult quickmin(System& system, const ForceField& force_field, double skin,
                        const MinimizeSettings& settings) {
  ForceEngine engine(force_field, skin);
  Particles& p = system.particles;
  const std::vector<Vec3> kept_velocity = p.velocity;
  std::vector<Vec3> v(p.size());
  MinimizeResult result;
  result.initial_energy = engine.compute(system).potential;
  const double dt = settings.timestep;
  for (; result.steps < settings.max_steps; ++result.steps) {
    result.max_force = largest_component(engine.force());
    if (result.max_force < settings.force_tolerance) {
      result.converged = true;
      break;
    }
    // Project the velocity on the force direction (zero if it points against it).
    const std::vector<Vec3>& f = engine.force();
    double vf = 0.0, ff = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) vf += dot(v[i], f[i]), ff += norm2(f[i]);
    const double scale = vf > 0.0 && ff > 0.0 ? vf / ff : 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) v[i] = f[i] * scale;
    for (std::size_t i = 0; i < p.size(); ++i) v[i] += f[i] * (dt / p.mass[i]);
    // Limit the largest step so that a huge overlap force cannot throw particles across
    // the box in one step.
    double vmax = 0.0;
    for (const Vec3& vi : v) vmax = std::max(vmax, norm(vi));
    const double step_scale =
        vmax * dt > settings.max_displacement ? settings.max_displacement / (vmax * dt) : 1.0;
    for (std::size_t i = 0; i < p.size(); ++i) p.position[i] += v[i] * (dt * step_scale);
    engine.compute(system, false);
  }
  engine.compute(system);
  result.max_force = largest_component(engine.force());
  result.converged = result.converged || result.max_force < settings.force_tolerance;
  result.final_energy = engine.last().potential;
  p.velocity = kept_velocity;
  return result;
}

}  // namespace deli
