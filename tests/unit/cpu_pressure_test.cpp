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

}  // namespace
}  // namespace deli
