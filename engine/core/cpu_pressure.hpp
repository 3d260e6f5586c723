#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace deli {

// The total of the "some" line of Linux's CPU pressure stall information (PSI, the kernel's
// Documentation/accounting/psi.rst): microseconds during which at least one runnable thread
// of the system waited for a CPU, since boot. `text`: /proc/pressure/cpu's; none where it
// has no such line.
std::optional<long long> cpu_stall_total_us(const std::string& text);

// The same read from /proc/pressure/cpu; none without the file (kernels before 4.20, or
// built without PSI).
std::optional<long long> cpu_stall_total_us();

// Whether a stall of `stall_us` (the growth of that total) over a window of `window_ns` says
// that other processes' threads crowd the CPUs: more than a third of the window. On this
// project's 2-core machine a second 2-thread run beside one stalled 55-99 % of 50 ms windows;
// a run alone up to 25 %, where a kernel thread or a light process woke while every CPU spun.
bool stall_means_crowded(long long stall_us, std::int64_t window_ns);

}  // namespace deli
