#pragma once

#include <memory>

#include "input/run_input.hpp"
#include "integrators/integrator.hpp"

namespace deli {

// The integrator the input's [integrator] table names, for its system, inside the
// [thermostat] when there is one, and putting the particles in spatial order every
// [neighbor] sort_every steps (ReorderingIntegrator: it reorders `input`'s system,
// constraints and force field). It keeps references to `input` and its force field, which
// must outlive it.
std::unique_ptr<Integrator> make_integrator(RunInput& input);
// The same without the sorting: the particles stay in the order they are in.
std::unique_ptr<Integrator> make_unsorted_integrator(const RunInput& input);

}  // namespace deli
