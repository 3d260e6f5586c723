#pragma once

#include <array>
#include <chrono>
#include <cstddef>

namespace deli {

// Where the step loop's time goes, as LAMMPS' end-of-run table: every moment between
// start() and stop() is charged to exactly one phase, the innermost one open (a force
// evaluation inside a position update is charged to the forces), so the phases add up to
// the loop time. One clock read per phase change: cheap enough for every step, never used
// per pair or per row.
enum class Phase : int {
  other,
  pair,
  neighbor,
  bonded,
  prediction,
  active_set,
  reflections,
  position_update,
  momentum_update,
  constraint_checks,
  thermostat,
  output,
  count
};
constexpr std::size_t phase_count = static_cast<std::size_t>(Phase::count);
const char* phase_name(Phase phase);

class PhaseTimer {
 public:
  using Clock = std::chrono::steady_clock;

  // Zeroes every phase and charges the time from now on to `other`.
  void start();
  // Charges the time up to now and stops charging.
  void stop();
  // Charges the time since the last change to the open phase, opens `phase` and returns
  // the one it replaces. Does nothing while stopped (steps run outside a timed loop).
  Phase enter(Phase phase) {
    if (!running_) return current_;
    const Clock::time_point now = Clock::now();
    spent_[static_cast<std::size_t>(current_)] += now - since_;
    since_ = now;
    const Phase previous = current_;
    current_ = phase;
    return previous;
  }
  std::array<double, phase_count> seconds() const;

 private:
  std::array<Clock::duration, phase_count> spent_{};
  Phase current_ = Phase::other;
  Clock::time_point since_;
  bool running_ = false;
};

// The timer of this thread's step loop (the engine runs one loop per thread).
PhaseTimer& phase_timer();

// Charges the enclosing scope to `phase`, then returns to the phase it interrupted.
class TimedPhase {
 public:
  explicit TimedPhase(Phase phase) : previous_(phase_timer().enter(phase)) {}
  ~TimedPhase() { phase_timer().enter(previous_); }
  TimedPhase(const TimedPhase&) = delete;
  TimedPhase& operator=(const TimedPhase&) = delete;

 private:
  Phase previous_;
};

}  // namespace deli
