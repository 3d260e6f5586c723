#pragma once

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

}  // namespace deli
