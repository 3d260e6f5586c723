#include "input/thermostat_input.hpp"

#include <cmath>

#include "constraints/equality_rank.hpp"

namespace deli {

std::optional<ThermostatSettings> read_thermostat(std::optional<TomlTable> t) {
  if (!t) return std::nullopt;
  ThermostatSettings s;
  s.kind = t->choice("type", {"langevin", "csvr"}) == "langevin" ? ThermostatKind::langevin
                                                                 : ThermostatKind::csvr;
  s.temperature = t->number("temperature");
  if (!(s.temperature > 0) || !std::isfinite(s.temperature))
    t->fail("must be a positive number (reduced units, k_B = 1)", "temperature");
  s.damping = t->number("damping");
  if (!(s.damping > 0) || !std::isfinite(s.damping)) {
    t->fail("must be a positive time (reduced units; LAMMPS' damp, 1/friction in OpenMM)",
            "damping");
  }
  const std::int64_t seed = t->integer("seed");
  if (seed < 0) t->fail("must not be negative", "seed");
  s.seed = static_cast<std::uint64_t>(seed);
  if (t->has("steps")) {
    s.until_step = t->integer("steps");
    if (s.until_step < 0)
      t->fail("must not be negative (omit it to thermostat the whole run)", "steps");
  }
  t->finish();
  return s;
}

DegreesOfFreedom run_degrees_of_freedom(const System& system, const ConstraintSet& constraints,
                                        const ForceFieldSpec& force_field,
                                        const std::optional<ThermostatSettings>& thermostat) {
  ExternalActions actions;
  for (int a = 0; a < 3; ++a) actions.periodic[a] = system.box.periodic(a);
  for (const Wall& wall : constraints.walls) {
    if (wall.kind == ConstraintKind::plane) {
      actions.directions.push_back(wall.normal);
    } else {
      actions.centres.push_back(wall.point);
    }
  }
  for (const Constraint& c : constraints.equalities) {
    if (c.kind == ConstraintKind::anchor) actions.centres.push_back(c.point);
  }
  if (force_field.gravity) actions.directions.push_back(*force_field.gravity);
  for (const ForceFieldSpec::Radial& radial : force_field.radial) {
    actions.centres.push_back(radial.center);
  }
  // Langevin kicks each particle on its own: no momentum is conserved. A Langevin
  // equilibration (`steps`) is counted as the constant-energy run it leads to, which
  // starts with the conserved momenta removed.
  actions.bath_on_each_particle =
      thermostat && thermostat->kind == ThermostatKind::langevin && thermostat->until_step < 0;
  // Rods count by their rank: a redundant rod (a braced rigid loop) removes no freedom.
  const std::size_t independent =
      independent_equalities(constraints.equalities, system.particles.position.data(),
                             system.particles.size(), system.box);
  return count_degrees_of_freedom(system.particles, independent, actions);
}

}  // namespace deli
