#include "core/cpu_quota.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <fstream>
#include <sstream>
#include <vector>

namespace deli {

namespace {

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, separator)) parts.push_back(part);
  return parts;
}

bool read_file(const std::string& path, std::string& text) {
  std::ifstream in(path);
  if (!in) return false;
  std::ostringstream all;
  all << in.rdbuf();
  text = all.str();
  return true;
}

// A cgroup directory's own quota in CPUs: v1's cpu.cfs_quota_us over cpu.cfs_period_us
// (-1: none), v2's cpu.max ("max PERIOD": none).
std::optional<double> own_limit(const std::string& dir, bool v2) {
  std::string text;
  double quota = -1.0, period = 0.0;
  if (v2) {
    if (!read_file(dir + "/cpu.max", text)) return std::nullopt;
    std::istringstream in(text);
    std::string q;
    if (!(in >> q >> period) || q == "max") return std::nullopt;
    try {
      quota = std::stod(q);
    } catch (const std::exception&) {
      return std::nullopt;
    }
  } else {
    if (!read_file(dir + "/cpu.cfs_quota_us", text)) return std::nullopt;
    std::istringstream quota_in(text);
    if (!(quota_in >> quota)) return std::nullopt;
    if (!read_file(dir + "/cpu.cfs_period_us", text)) return std::nullopt;
    std::istringstream period_in(text);
    if (!(period_in >> period)) return std::nullopt;
  }
  if (!(quota > 0.0) || !(period > 0.0)) return std::nullopt;
  return quota / period;
}

// The smallest quota from `dir` up to the hierarchy's mount point `top`: a parent's quota
// caps its children's.
std::optional<double> limit_up_to(std::string dir, const std::string& top, bool v2) {
  std::optional<double> smallest;
  for (;;) {
    const std::optional<double> own = own_limit(dir, v2);
    if (own && (!smallest || *own < *smallest)) smallest = own;
    if (dir.size() <= top.size()) break;
    const std::size_t slash = dir.find_last_of('/');
    if (slash == std::string::npos || slash < top.size()) break;
    dir.resize(std::max(slash, top.size()));
  }
  return smallest;
}

struct Mount {
  std::string root, point;  // the cgroup path the mount shows, and where
};

// The cgroup mounts: v1's holding the cpu controller, and v2's.
void find_mounts(const std::string& mountinfo, std::optional<Mount>& v1, std::optional<Mount>& v2) {
  std::istringstream lines(mountinfo);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream in(line);
    std::vector<std::string> fields;
    std::string field;
    while (in >> field) fields.push_back(field);
    const auto dash = std::find(fields.begin(), fields.end(), "-");
    if (fields.size() < 5 || dash == fields.end() || fields.end() - dash < 2) continue;
    const std::string& type = dash[1];
    const Mount mount{fields[3], fields[4]};
    if (type == "cgroup2") {
      if (!v2) v2 = mount;
    } else if (type == "cgroup" && fields.end() - dash >= 4) {
      const std::vector<std::string> options = split(dash[3], ',');
      if (!v1 && std::find(options.begin(), options.end(), "cpu") != options.end()) v1 = mount;
    }
  }
}

// The process's cgroup path under a mount showing `mount_root`: relative to it, or the
// mount's top where the process's path lies outside it (a container's namespace).
std::string path_under(const std::string& path, const std::string& mount_root) {
  if (mount_root == "/") return path == "/" ? "" : path;
  if (path == mount_root) return "";
  if (path.compare(0, mount_root.size() + 1, mount_root + "/") == 0) {
    return path.substr(mount_root.size());
  }
  return "";
}

}  // namespace

std::optional<double> cgroup_cpu_limit(const std::string& cgroup, const std::string& mountinfo,
                                       const std::string& root) {
  std::optional<Mount> v1_mount, v2_mount;
  find_mounts(mountinfo, v1_mount, v2_mount);
  std::optional<double> smallest;
  auto consider = [&](const std::optional<double>& limit) {
    if (limit && (!smallest || *limit < *smallest)) smallest = limit;
  };
  std::istringstream lines(cgroup);
  std::string line;
  while (std::getline(lines, line)) {
    // hierarchy:controllers:path (the path may itself hold colons)
    const std::size_t first = line.find(':');
    const std::size_t second = first == std::string::npos ? first : line.find(':', first + 1);
    if (second == std::string::npos) continue;
    const std::string hierarchy = line.substr(0, first);
    const std::vector<std::string> controllers =
        split(line.substr(first + 1, second - first - 1), ',');
    const std::string path = line.substr(second + 1);
    const bool v2 = hierarchy == "0" && controllers.empty();
    const std::optional<Mount>& mount = v2 ? v2_mount : v1_mount;
    if (!mount) continue;
    if (!v2 && std::find(controllers.begin(), controllers.end(), "cpu") == controllers.end()) {
      continue;
    }
    const std::string top = root + mount->point;
    consider(limit_up_to(top + path_under(path, mount->root), top, v2));
  }
  return smallest;
}

std::optional<double> process_cpu_limit() {
  static const std::optional<double> limit = [] {
    std::string cgroup, mountinfo;
    if (!read_file("/proc/self/cgroup", cgroup) || !read_file("/proc/self/mountinfo", mountinfo)) {
      return std::optional<double>{};
    }
    return cgroup_cpu_limit(cgroup, mountinfo);
  }();
  return limit;
}

int cpus_of_limit(double limit) {
  return std::max(1, static_cast<int>(std::ceil(limit)));
}

std::optional<int> quota_cpus() {
  const std::optional<double> limit = process_cpu_limit();
  if (!limit) return std::nullopt;
  return cpus_of_limit(*limit);
}

}  // namespace deli
