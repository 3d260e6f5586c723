// cpu_stall_total_us() reads the "some" line's total of /proc/pressure/cpu, in the format of
// the kernel's Documentation/accounting/psi.rst (the expected values are the texts' own).
#include "core/cpu_pressure.hpp"

#include <gtest/gtest.h>

namespace deli {
namespace {

TEST(CpuPressure, TheSomeLinesTotalInMicroseconds) {
  EXPECT_EQ(cpu_stall_total_us("some avg10=4.15 avg60=17.22 avg300=24.76 total=435666768\n"
                               "full avg10=0.00 avg60=0.00 avg300=0.00 total=0\n"),
            435666768LL);
  // Kernels before 5.13 write no "full" line for the CPU.
  EXPECT_EQ(cpu_stall_total_us("some avg10=0.00 avg60=0.00 avg300=0.00 total=12\n"), 12LL);
}

TEST(CpuPressure, NothingWithoutASomeLineOrItsTotal) {
  EXPECT_FALSE(cpu_stall_total_us(""));
  EXPECT_FALSE(cpu_stall_total_us("full avg10=0.00 avg60=0.00 avg300=0.00 total=7\n"));
  EXPECT_FALSE(cpu_stall_total_us("some avg10=0.00 avg60=0.00 avg300=0.00\n"));
  EXPECT_FALSE(cpu_stall_total_us("some avg10=0.00 total=x\n"));
}

// The windows' stalls measured on this project's 2-core machine (/proc/pressure/cpu read every
// 50 ms): a 2-thread run of the 32000-sphere fluid alone stalled up to 25 % of a window
// (15 %, 11 % and below in the others), two such runs at once 55-99 %. At a tenth, the
// threshold before, 11 of 81 such runs alone waited passively for a second.
TEST(CpuPressure, ARunAlonesStallIsNoCrowdASecondRunsIs) {
  constexpr std::int64_t window_ns = 50'000'000;
  EXPECT_FALSE(stall_means_crowded(12'600, window_ns));  // 25 %: alone
  EXPECT_FALSE(stall_means_crowded(7'700, window_ns));   // 15 %: alone
  EXPECT_TRUE(stall_means_crowded(27'300, window_ns));   // 55 %: beside a second run
  EXPECT_TRUE(stall_means_crowded(49'500, window_ns));   // 99 %
  EXPECT_FALSE(stall_means_crowded(10, 0));              // no window
}

}  // namespace
}  // namespace deli
