// The CPUs a cgroup quota allows, read from trees laid out as the kernel's cgroup file
// systems show them (Documentation/admin-guide/cgroup-v1/cgroups.rst and cgroup-v2.rst:
// /proc/self/cgroup lines "hierarchy:controllers:path", v1's cpu.cfs_quota_us and
// cpu.cfs_period_us with -1 for none, v2's cpu.max "QUOTA PERIOD" or "max PERIOD"). The
// /proc texts follow proc(5)'s formats, as this project's machine (v1 and v2 side by side)
// and a systemd host and a Docker container (v2) write them. Expected values: quota over
// period by definition, the smallest along the path (a parent's quota caps its children).
#include "core/cpu_quota.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace deli {
namespace {

// A cgroup tree of the test's own under the temporary folder, removed with it.
class FakeRoot {
 public:
  FakeRoot()
      : root_(std::filesystem::temp_directory_path() /
              ("deli-cgroup-" +
               std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "-" +
               std::to_string(::getpid()))) {
    std::filesystem::create_directories(root_);
  }
  FakeRoot(const FakeRoot&) = delete;
  FakeRoot& operator=(const FakeRoot&) = delete;
  ~FakeRoot() { std::filesystem::remove_all(root_); }

  void write(const std::string& path, const std::string& text) const {
    const std::filesystem::path file = root_ / path.substr(1);
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file) << text;
  }
  std::string path() const { return root_.string(); }

 private:
  std::filesystem::path root_;
};

// This project's machine: cgroup v1 controllers each mounted alone, v2 beside them.
const std::string kHybridMounts =
    "31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755\n"
    "32 31 0:29 / /sys/fs/cgroup/cpu rw,relatime - cgroup cgroup rw,cpu\n"
    "33 31 0:30 / /sys/fs/cgroup/cpuacct rw,relatime - cgroup cgroup rw,cpuacct\n"
    "34 31 0:31 / /sys/fs/cgroup/cpuset rw,relatime - cgroup cgroup rw,cpuset\n"
    "41 31 0:38 / /sys/fs/cgroup/unified rw,relatime - cgroup2 cgroup2 rw\n";

TEST(CpuQuota, CgroupV1QuotaOverPeriod) {
  const FakeRoot root;
  root.write("/sys/fs/cgroup/cpu/job/cpu.cfs_quota_us", "150000\n");
  root.write("/sys/fs/cgroup/cpu/job/cpu.cfs_period_us", "100000\n");
  root.write("/sys/fs/cgroup/cpu/cpu.cfs_quota_us", "-1\n");
  root.write("/sys/fs/cgroup/cpu/cpu.cfs_period_us", "100000\n");
  const std::string cgroup = "3:cpuset:/\n2:cpuacct:/\n1:cpu:/job\n0::/\n";
  const std::optional<double> limit = cgroup_cpu_limit(cgroup, kHybridMounts, root.path());
  ASSERT_TRUE(limit.has_value());
  EXPECT_DOUBLE_EQ(*limit, 1.5);
  EXPECT_EQ(cpus_of_limit(*limit), 2);
  // No quota anywhere on the path (-1): no limit.
  EXPECT_FALSE(cgroup_cpu_limit("1:cpu:/\n", kHybridMounts, root.path()).has_value());
}

TEST(CpuQuota, CgroupV1CombinedControllersAndAnAncestorsQuota) {
  const FakeRoot root;
  const std::string mounts =
      "25 24 0:22 / /sys/fs/cgroup/cpu,cpuacct rw,nosuid - cgroup cgroup rw,cpu,cpuacct\n"
      "26 24 0:23 / /sys/fs/cgroup/cpuset rw,nosuid - cgroup cgroup rw,cpuset\n";
  // The parent's 2 CPUs cap the child's 3; cpuset's files are not read for the quota.
  root.write("/sys/fs/cgroup/cpu,cpuacct/slurm/cpu.cfs_quota_us", "200000");
  root.write("/sys/fs/cgroup/cpu,cpuacct/slurm/cpu.cfs_period_us", "100000");
  root.write("/sys/fs/cgroup/cpu,cpuacct/slurm/job7/cpu.cfs_quota_us", "300000");
  root.write("/sys/fs/cgroup/cpu,cpuacct/slurm/job7/cpu.cfs_period_us", "100000");
  root.write("/sys/fs/cgroup/cpuset/slurm/job7/cpu.cfs_quota_us", "50000");
  root.write("/sys/fs/cgroup/cpuset/slurm/job7/cpu.cfs_period_us", "100000");
  const std::string cgroup = "4:cpuset:/slurm/job7\n3:cpu,cpuacct:/slurm/job7\n";
  const std::optional<double> limit = cgroup_cpu_limit(cgroup, mounts, root.path());
  ASSERT_TRUE(limit.has_value());
  EXPECT_DOUBLE_EQ(*limit, 2.0);
}

TEST(CpuQuota, CgroupV2CpuMaxAlongThePath) {
  const FakeRoot root;
  const std::string mounts =
      "30 23 0:26 / /sys/fs/cgroup rw,nosuid,nodev,noexec,relatime shared:4 - cgroup2 cgroup2 "
      "rw,nsdelegate,memory_recursiveprot\n";
  root.write("/sys/fs/cgroup/system.slice/cpu.max", "250000 100000\n");
  root.write("/sys/fs/cgroup/system.slice/deli.service/cpu.max", "max 100000\n");
  const std::string cgroup = "0::/system.slice/deli.service\n";
  const std::optional<double> limit = cgroup_cpu_limit(cgroup, mounts, root.path());
  ASSERT_TRUE(limit.has_value());
  EXPECT_DOUBLE_EQ(*limit, 2.5);
  EXPECT_EQ(cpus_of_limit(*limit), 3);
  // A quota below one CPU still runs one thread.
  root.write("/sys/fs/cgroup/system.slice/deli.service/cpu.max", "20000 100000\n");
  EXPECT_DOUBLE_EQ(cgroup_cpu_limit(cgroup, mounts, root.path()).value_or(-1.0), 0.2);
  EXPECT_EQ(cpus_of_limit(0.2), 1);
}

TEST(CpuQuota, ContainerSeesItsCgroupAtTheMountsTop) {
  // Docker without a cgroup namespace: the container's mount shows its own cgroup as the
  // mount's root, and /proc/self/cgroup names the same path.
  const FakeRoot root;
  const std::string mounts =
      "688 680 0:26 /docker/4f1e /sys/fs/cgroup ro,nosuid - cgroup2 cgroup2 rw,nsdelegate\n";
  root.write("/sys/fs/cgroup/cpu.max", "100000 100000\n");
  const std::optional<double> limit = cgroup_cpu_limit("0::/docker/4f1e\n", mounts, root.path());
  ASSERT_TRUE(limit.has_value());
  EXPECT_DOUBLE_EQ(*limit, 1.0);
  // A path outside the mount's root (another namespace's view): the mount's top is read.
  EXPECT_DOUBLE_EQ(cgroup_cpu_limit("0::/elsewhere\n", mounts, root.path()).value_or(-1.0), 1.0);
}

TEST(CpuQuota, NoFilesOrUnreadableValuesSetNoLimit) {
  const FakeRoot root;
  EXPECT_FALSE(cgroup_cpu_limit("1:cpu:/job\n0::/job\n", kHybridMounts, root.path()).has_value());
  root.write("/sys/fs/cgroup/cpu/job/cpu.cfs_quota_us", "lots\n");
  root.write("/sys/fs/cgroup/cpu/job/cpu.cfs_period_us", "100000\n");
  root.write("/sys/fs/cgroup/unified/job/cpu.max", "100000 0\n");
  EXPECT_FALSE(cgroup_cpu_limit("1:cpu:/job\n0::/job\n", kHybridMounts, root.path()).has_value());
  EXPECT_FALSE(cgroup_cpu_limit("", "", root.path()).has_value());
}

}  // namespace
}  // namespace deli
