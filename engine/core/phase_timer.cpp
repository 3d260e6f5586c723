#include "core/phase_timer.hpp"

namespace deli {

const char* phase_name(Phase phase) {
  switch (phase) {
    case Phase::other:
      return "other";
    case Phase::pair:
      return "pair forces";
    case Phase::neighbor:
      return "neighbour list";
    case Phase::bonded:
      return "bonded terms";
    case Phase::prediction:
      return "gvi prediction";
    case Phase::active_set:
      return "gvi active set";
    case Phase::reflections:
      return "gvi reflections";
    case Phase::position_update:
      return "gvi position update";
    case Phase::momentum_update:
      return "gvi momentum update";
    case Phase::constraint_checks:
      return "constraint checks";
    case Phase::thermostat:
      return "thermostat";
    case Phase::output:
      return "output";
    case Phase::count:
      break;
  }
  return "?";
}

void PhaseTimer::start() {
  spent_.fill(Clock::duration::zero());
  current_ = Phase::other;
  since_ = Clock::now();
  running_ = true;
}

void PhaseTimer::stop() {
  if (!running_) return;
  spent_[static_cast<std::size_t>(current_)] += Clock::now() - since_;
  running_ = false;
}

std::array<double, phase_count> PhaseTimer::seconds() const {
  std::array<double, phase_count> out{};
  for (std::size_t k = 0; k < phase_count; ++k) {
    out[k] = std::chrono::duration<double>(spent_[k]).count();
  }
  return out;
}

PhaseTimer& phase_timer() {
  thread_local PhaseTimer timer;
  return timer;
}

}  // namespace deli
