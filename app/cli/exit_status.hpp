#pragma once

namespace deli {

// deli's exit statuses (README "Exit status"), one per kind of outcome, so that scripts can
// tell a bad input from a simulation that stopped or engines that disagree.
constexpr int kExitSuccess = 0;
constexpr int kExitInputError = 1;         // the input, a file it names or an argument is wrong
constexpr int kExitUsage = 2;              // no command, or an unknown one
constexpr int kExitSimulationStopped = 3;  // blow-up, solver failure, write failure
constexpr int kExitDisagreement = 4;       // deli validate: an engine disagrees beyond tolerance
constexpr int kExitInterrupted = 130;      // SIGINT/SIGTERM: checkpoint written (128 + SIGINT)

}  // namespace deli
