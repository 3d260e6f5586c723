// The run's timing breakdown: every moment of the loop is charged to one phase.
#include "core/phase_timer.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace deli {
namespace {

void busy(std::chrono::milliseconds span) {
  const auto end = std::chrono::steady_clock::now() + span;
  while (std::chrono::steady_clock::now() < end) {
  }
}

TEST(PhaseTimer, NestedPhaseIsChargedToTheInnerOneOnly) {
  PhaseTimer& timer = phase_timer();
  const auto start = std::chrono::steady_clock::now();
  timer.start();
  {
    const TimedPhase outer(Phase::position_update);
    busy(std::chrono::milliseconds(20));
    {
      const TimedPhase inner(Phase::pair);
      busy(std::chrono::milliseconds(20));
    }
  }
  timer.stop();
  const double total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto s = timer.seconds();
  double sum = 0;
  for (double t : s) sum += t;
  EXPECT_GE(s[static_cast<std::size_t>(Phase::position_update)], 0.019);
  EXPECT_GE(s[static_cast<std::size_t>(Phase::pair)], 0.019);
  EXPECT_LT(s[static_cast<std::size_t>(Phase::position_update)], total - 0.019);
  EXPECT_LE(sum, total);
  EXPECT_GE(sum, 0.039);
}

TEST(PhaseTimer, StoppedTimerChargesNothing) {
  PhaseTimer& timer = phase_timer();
  timer.start();
  timer.stop();
  {
    const TimedPhase outside(Phase::reflections);
    busy(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(timer.seconds()[static_cast<std::size_t>(Phase::reflections)], 0.0);
}

}  // namespace
}  // namespace deli
