#pragma once

#include <optional>

#include "constraints/constraint_set.hpp"
#include "force_field_spec.hpp"
#include "input/toml_table.hpp"
#include "simulation/degrees_of_freedom.hpp"
#include "system/system.hpp"
#include "thermostats/thermostat.hpp"

namespace deli {

// Reads [thermostat]: type = "langevin" | "csvr", temperature, damping (time units), seed,
// and optionally steps (the thermostat acts for the run's first `steps` steps, then the
// run goes on at constant energy). Nothing when the table is absent.
std::optional<ThermostatSettings> read_thermostat(std::optional<TomlTable> table);

// The run's degrees of freedom: its rods and strings, and the momenta its walls, strings,
// external fields, box and thermostat leave conserved.
DegreesOfFreedom run_degrees_of_freedom(const System& system, const ConstraintSet& constraints,
                                        const ForceFieldSpec& force_field,
                                        const std::optional<ThermostatSettings>& thermostat);

}  // namespace deli
