#pragma once

#include <optional>
#include <string>

namespace deli {

// The CPUs a cgroup CPU quota lets this process use (a container's `docker run --cpus`,
// Kubernetes' CPU limit, systemd's CPUQuota): quota over period, the smallest along the
// process's cgroup and its ancestors; none without a quota. Not in the affinity mask that
// OpenMP's default thread count and `nproc` count: on a 16-core host a container limited to
// 2 CPUs would otherwise run 16 threads, which the scheduler throttles once they have used
// the quota's time (the default input on this 2-core machine in a cgroup of 1 CPU: 3.11 s
// for 3000 steps on 2 threads, 2.08 s on 1).
// cgroup: /proc/self/cgroup's text; mountinfo: /proc/self/mountinfo's; root: prefixed to the
// mount points read (a test's tree; "" for the real one). cgroup v1 (cpu.cfs_quota_us and
// cpu.cfs_period_us) and v2 (cpu.max); a file missing or unreadable sets no limit.
std::optional<double> cgroup_cpu_limit(const std::string& cgroup, const std::string& mountinfo,
                                       const std::string& root = "");

// cgroup_cpu_limit() of this process, read once.
std::optional<double> process_cpu_limit();

// CPUs a limit of `limit` CPUs lets threads run on: rounded up, at least 1.
int cpus_of_limit(double limit);

// cpus_of_limit(process_cpu_limit()); none without a quota. The default thread count keeps
// within it. The threads' waiting does not (core/thread_team.hpp's cpus_available() is the
// affinity mask's): up to the mask's CPUs the threads do run at once until the quota's time
// is spent, and sleeping waits then cost more than spinning (the default input in a cgroup
// of 1 CPU on 2 threads: 5.8 s for 3000 steps waiting as `passive` does, 3.5 s spinning).
std::optional<int> quota_cpus();

}  // namespace deli
