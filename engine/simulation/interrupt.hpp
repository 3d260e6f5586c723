#pragma once

namespace deli {

// SIGINT and SIGTERM only raise a flag: the run loop finishes the current step, and the
// command writes a checkpoint and flushes before exiting.
void install_interrupt_handlers();
bool interrupt_requested();

}  // namespace deli
