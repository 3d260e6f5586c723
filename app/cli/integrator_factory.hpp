#pragma once

#include <memory>

#include "input/run_input.hpp"
#include "integrators/integrator.hpp"

namespace deli {

// The integrator the input's [integrator] table names, for its system, inside the
// [thermostat] when there is one. It keeps references to input's force field.
std::unique_ptr<Integrator> make_integrator(const RunInput& input);

}  // namespace deli
