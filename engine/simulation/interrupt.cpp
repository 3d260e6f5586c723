#include "simulation/interrupt.hpp"

#include <signal.h>
#include <unistd.h>

#include <csignal>

namespace deli {

namespace {
volatile std::sig_atomic_t requested = 0;
// The first signal asks for a clean stop after the step; a second one (the step does not
// end, or the user will not wait) ends the process at once. Every thermo row and frame was
// flushed when written, so what was written stays readable; no checkpoint is taken.
extern "C" void on_signal(int) {
  if (requested) {
    static const char message[] =
        "\ndeli: second interrupt: stopped at once, without a checkpoint (outputs are kept as "
        "flushed)\n";
    [[maybe_unused]] const ssize_t written = write(STDERR_FILENO, message, sizeof message - 1);
    _exit(130);
  }
  requested = 1;
}
}  // namespace

void install_interrupt_handlers() {
  // Each signal blocks both while its handler runs: a SIGTERM arriving inside the SIGINT
  // handler between its test and its set of `requested` would otherwise also see a first
  // signal, and neither would end the process.
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaddset(&action.sa_mask, SIGINT);
  sigaddset(&action.sa_mask, SIGTERM);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool interrupt_requested() {
  return requested != 0;
}

}  // namespace deli
