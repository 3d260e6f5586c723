#include "constraints/clusters.hpp"

#include <algorithm>
#include <numeric>
#include <unordered_map>

namespace deli {

namespace {
std::int32_t root(std::vector<std::int32_t>& parent, std::int32_t a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}
}  // namespace

std::vector<Cluster> find_clusters(const std::vector<Constraint>& rows,
                                   std::size_t particle_count) {
  std::vector<std::int32_t> parent(particle_count);
  std::iota(parent.begin(), parent.end(), 0);
  for (const Constraint& c : rows) {
    if (c.j < 0) continue;
    const std::int32_t a = root(parent, c.i), b = root(parent, c.j);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // root = smallest index
  }
  std::unordered_map<std::int32_t, std::size_t> cluster_of_root;
  std::vector<Cluster> clusters;
  std::vector<bool> seen(particle_count, false);
  // Rows in order; a cluster is created at its first row, then renumbered by its root.
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const std::int32_t top = root(parent, rows[r].i);
    auto [it, added] = cluster_of_root.try_emplace(top, clusters.size());
    if (added) clusters.emplace_back();
    Cluster& cl = clusters[it->second];
    cl.rows.push_back(static_cast<std::int32_t>(r));
    for (std::int32_t p : {rows[r].i, rows[r].j}) {
      if (p >= 0 && !seen[p]) {
        seen[p] = true;
        cl.particles.push_back(p);
      }
    }
  }
  for (Cluster& cl : clusters) std::sort(cl.particles.begin(), cl.particles.end());
  std::sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) {
    return a.particles.front() < b.particles.front();
  });
  return clusters;
}

LocalCluster localize(const Cluster& cluster, const std::vector<Constraint>& rows,
                      const std::vector<double>& mass) {
  LocalCluster local;
  local.particles = cluster.particles;
  for (std::int32_t p : cluster.particles) local.inverse_mass.push_back(1.0 / mass[p]);
  auto local_index = [&](std::int32_t global) {
    if (global < 0) return std::int32_t{-1};
    return static_cast<std::int32_t>(
        std::lower_bound(cluster.particles.begin(), cluster.particles.end(), global) -
        cluster.particles.begin());
  };
  for (std::int32_t r : cluster.rows) {
    Constraint c = rows[r];
    c.i = local_index(c.i);
    c.j = local_index(c.j);
    local.rows.push_back(c);
    local.global_rows.push_back(r);
  }
  return local;
}

}  // namespace deli
