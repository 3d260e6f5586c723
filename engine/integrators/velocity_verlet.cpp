#include "integrators/velocity_verlet.hpp"

#include "core/parallel.hpp"

namespace deli {

VelocityVerlet::VelocityVerlet(const ForceField& force_field, double skin, double timestep)
    : engine_(force_field, skin), dt_(timestep) {}

void VelocityVerlet::setup(System& system) {
  engine_.compute(system);
}

void VelocityVerlet::half_kick(Particles& p) const {
  const std::vector<Vec3>& f = engine_.force();
  parallel_for(p.size(), [&](std::size_t i) { p.velocity[i] += f[i] * (0.5 * dt_ / p.mass[i]); });
}

void VelocityVerlet::step(System& system, bool tally) {
  Particles& p = system.particles;
  // The kick and the drift in one pass (one parallel region fewer per step).
  const std::vector<Vec3>& f = engine_.force();
  parallel_for(p.size(), [&](std::size_t i) {
    p.velocity[i] += f[i] * (0.5 * dt_ / p.mass[i]);
    p.position[i] += p.velocity[i] * dt_;
  });
  system.step += 1;
  system.time += dt_;
  engine_.compute(system, tally);
  half_kick(p);
}

}  // namespace deli
