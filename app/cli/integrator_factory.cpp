#include "cli/integrator_factory.hpp"

#include "integrators/collision_integrator.hpp"
#include "integrators/direct_substitution.hpp"
#include "integrators/gvi.hpp"
#include "integrators/reordering_integrator.hpp"
#include "integrators/thermostatted_integrator.hpp"
#include "integrators/velocity_verlet.hpp"

namespace deli {

namespace {
std::unique_ptr<Integrator> make_constant_energy_integrator(const RunInput& input) {
  const Particles& particles = input.system.particles;
  if (input.integrator == "verlet") {
    return std::make_unique<VelocityVerlet>(*input.force_field, input.skin, input.timestep);
  }
  if (input.integrator == "direct") {
    return std::make_unique<DirectSubstitution>(
        *input.force_field, input.constraints, input.timestep, input.skin, input.direct, particles);
  }
  if (input.integrator == "collision") {
    return std::make_unique<CollisionIntegrator>(*input.force_field, input.constraints,
                                                 input.timestep, input.skin, input.collision,
                                                 particles);
  }
  // gvi, dsi, midpoint: one integrator, options
  return std::make_unique<Gvi>(*input.force_field, input.constraints, input.gvi, particles);
}
}  // namespace

std::unique_ptr<Integrator> make_unsorted_integrator(const RunInput& input) {
  std::unique_ptr<Integrator> integrator = make_constant_energy_integrator(input);
  if (!input.thermostat) return integrator;
  return std::make_unique<ThermostattedIntegrator>(std::move(integrator), *input.thermostat,
                                                   input.degrees_of_freedom);
}

std::unique_ptr<Integrator> make_integrator(RunInput& input) {
  std::unique_ptr<Integrator> integrator = make_unsorted_integrator(input);
  if (input.sort_every == 0) return integrator;
  return std::make_unique<ReorderingIntegrator>(
      std::move(integrator),
      [&input](const ParticleOrder& order) {
        reorder_run_input(input, order);
        return make_unsorted_integrator(input);
      },
      input.sort_every);
}

}  // namespace deli
