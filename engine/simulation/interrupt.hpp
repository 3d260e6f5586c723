#pragma once

namespace deli {

// SIGINT and SIGTERM only raise a flag: the run loop finishes the current step, and the
// command writes a checkpoint and flushes before exiting. Loops inside a step that may run
// long (the collision integrator's events) check the flag and stop the run. A second
// signal ends the process at once (exit status 130).
void install_interrupt_handlers();
bool interrupt_requested();

}  // namespace deli
