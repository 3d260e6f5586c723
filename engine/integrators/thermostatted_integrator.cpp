#include "integrators/thermostatted_integrator.hpp"

#include "core/phase_timer.hpp"
#include "simulation/thermo.hpp"

namespace deli {

namespace {
// Marks the thermostat's numbers at the end of a checkpoint's integrator state.
constexpr double thermostat_state_tag = 7.3e6;
constexpr std::size_t thermostat_state_size = 5;
}  // namespace

ThermostattedIntegrator::ThermostattedIntegrator(std::unique_ptr<Integrator> inner,
                                                 const ThermostatSettings& settings,
                                                 const DegreesOfFreedom& dof)
    : ForwardingIntegrator(std::move(inner)),
      settings_(settings),
      dof_(dof),
      thermostat_(make_thermostat(settings, dof)) {}

std::string ThermostattedIntegrator::name() const {
  return inner_->name() + (settings_.kind == ThermostatKind::langevin ? "+langevin" : "+csvr");
}

void ThermostattedIntegrator::act(System& system, std::int64_t step, int half) {
  const TimedPhase timed(Phase::thermostat);
  const double before = kinetic_energy(system.particles);
  thermostat_->apply(system.particles, step, half, 0.5 * inner_->timestep());
  if (thermostat_->needs_projection()) inner_->project_velocities(system);
  bath_energy_ += kinetic_energy(system.particles) - before;
}

void ThermostattedIntegrator::step(System& system, bool tally) {
  const std::int64_t from = system.step;
  const bool active = settings_.until_step < 0 || from < settings_.until_step;
  if (active) act(system, from, 0);
  inner_->step(system, tally);
  if (active) act(system, system.step, 1);
  if (system.step == settings_.until_step) {
    // The constant-energy run starts without the momenta it conserves (the bath's random
    // walk of the centre of mass): a rigid motion, which leaves rods and contacts alone.
    const double before = kinetic_energy(system.particles);
    remove_conserved_momenta(system.particles, dof_);
    bath_energy_ += kinetic_energy(system.particles) - before;
  }
}

std::vector<double> ThermostattedIntegrator::saved_state() const {
  std::vector<double> state = inner_->saved_state();
  // The seed as two exact 32-bit halves; the random sequence itself is a function of the step.
  state.insert(state.end(),
               {thermostat_state_tag, static_cast<double>(settings_.seed & 0xffffffffu),
                static_cast<double>(settings_.seed >> 32),
                static_cast<double>(static_cast<int>(settings_.kind)), bath_energy_});
  return state;
}

std::vector<double> ThermostattedIntegrator::state_in_order(
    const std::vector<double>& state, const std::vector<std::int32_t>& order) const {
  const auto inner_end = state.end() - static_cast<std::ptrdiff_t>(thermostat_state_size);
  std::vector<double> out =
      inner_->state_in_order(std::vector<double>(state.begin(), inner_end), order);
  out.insert(out.end(), inner_end, state.end());
  return out;
}

void ThermostattedIntegrator::restore_state(const std::vector<double>& state,
                                            const System& system) {
  if (state.size() < thermostat_state_size ||
      state[state.size() - thermostat_state_size] != thermostat_state_tag) {
    throw InputError(
        "the checkpoint carries no thermostat state: it was written by a run without "
        "this input's [thermostat]; restart with the input that wrote it");
  }
  const double* own = state.data() + state.size() - thermostat_state_size + 1;
  const auto seed = static_cast<std::uint64_t>(own[0]) | (static_cast<std::uint64_t>(own[1]) << 32);
  if (seed != settings_.seed || own[2] != static_cast<double>(static_cast<int>(settings_.kind))) {
    throw InputError("the checkpoint was written with another thermostat (seed " +
                     std::to_string(seed) + ") than this input's [thermostat] (seed " +
                     std::to_string(settings_.seed) + "); restart with the input that wrote it");
  }
  inner_->restore_state(std::vector<double>(state.begin(), state.end() - thermostat_state_size),
                        system);
  bath_energy_ = own[3];
}

}  // namespace deli
