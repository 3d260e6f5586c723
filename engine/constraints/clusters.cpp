#include "constraints/clusters.hpp"

#include <algorithm>
#include <numeric>

#include "constraints/union_find.hpp"

namespace deli {

std::vector<Cluster> find_clusters(const std::vector<Constraint>& rows,
                                   std::size_t particle_count) {
  std::vector<Cluster> clusters;
  find_clusters(rows, particle_count, clusters);
  return clusters;
}

void find_clusters(const std::vector<Constraint>& rows, std::size_t particle_count,
                   std::vector<Cluster>& clusters) {
  // Scratch kept between calls (this runs several times a step, often with a handful of
  // contact rows among thousands of particles): outside a call parent[p] == p and
  // cluster_of_root[p] == -1 for every p; a call touches, and then resets, only the
  // particles its rows name.
  thread_local std::vector<std::int32_t> parent, cluster_of_root, touched;
  if (parent.size() < particle_count) {
    const std::size_t before = parent.size();
    parent.resize(particle_count);
    std::iota(parent.begin() + static_cast<std::ptrdiff_t>(before), parent.end(),
              static_cast<std::int32_t>(before));
    cluster_of_root.resize(particle_count, -1);
  }
  constexpr std::int32_t named = -2;  // in cluster_of_root: named by a row, no cluster yet
  touched.clear();
  auto name = [&](std::int32_t p) {
    if (cluster_of_root[p] == -1) cluster_of_root[p] = named, touched.push_back(p);
  };
  for (const Constraint& c : rows) {
    name(c.i);
    if (c.j < 0) continue;
    name(c.j);
    const std::int32_t a = union_find_root(parent, c.i), b = union_find_root(parent, c.j);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // root = smallest index
  }
  // A component's root is its smallest particle, so visiting the particles in ascending
  // order makes the clusters in the order of their first particle, each particle list
  // ascending: the named particles sorted when few, else all particles scanned.
  if (touched.size() * 8 < particle_count) {
    std::sort(touched.begin(), touched.end());
  } else {
    touched.clear();
    for (std::size_t p = 0; p < particle_count; ++p) {
      if (cluster_of_root[p] == named) touched.push_back(static_cast<std::int32_t>(p));
    }
  }
  // Each cluster's particle and row counts first, so that every list is allocated once.
  thread_local std::vector<std::int32_t> member_count, row_count, cluster_of_row;
  member_count.clear();
  for (const std::int32_t p : touched) {
    const std::int32_t top = union_find_root(parent, p);
    if (cluster_of_root[top] < 0) {
      cluster_of_root[top] = static_cast<std::int32_t>(member_count.size());
      member_count.push_back(0);
    }
    ++member_count[cluster_of_root[top]];
  }
  // Clusters beyond this call's count wait in `spare` with their storage.
  thread_local std::vector<Cluster> spare;
  for (; clusters.size() > member_count.size(); clusters.pop_back()) {
    spare.push_back(std::move(clusters.back()));
  }
  for (; clusters.size() < member_count.size() && !spare.empty(); spare.pop_back()) {
    clusters.push_back(std::move(spare.back()));
  }
  clusters.resize(member_count.size());
  for (std::size_t k = 0; k < clusters.size(); ++k) {
    clusters[k].particles.clear();
    clusters[k].rows.clear();
    clusters[k].particles.reserve(member_count[k]);
  }
  for (const std::int32_t p : touched) {
    clusters[cluster_of_root[union_find_root(parent, p)]].particles.push_back(p);
  }
  row_count.assign(clusters.size(), 0);
  cluster_of_row.resize(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    cluster_of_row[r] = cluster_of_root[union_find_root(parent, rows[r].i)];
    ++row_count[cluster_of_row[r]];
  }
  for (std::size_t k = 0; k < clusters.size(); ++k) clusters[k].rows.reserve(row_count[k]);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    clusters[cluster_of_row[r]].rows.push_back(static_cast<std::int32_t>(r));
  }
  for (const std::int32_t p : touched) parent[p] = p, cluster_of_root[p] = -1;
}

LocalCluster localize(const Cluster& cluster, const std::vector<Constraint>& rows,
                      const std::vector<double>& mass) {
  LocalCluster local;
  localize(cluster, rows, mass, local);
  return local;
}

void localize(const Cluster& cluster, const std::vector<Constraint>& rows,
              const std::vector<double>& mass, LocalCluster& local) {
  local.particles = cluster.particles;
  local.inverse_mass.clear();
  local.rows.clear();
  local.global_rows.clear();
  local.inverse_mass.reserve(cluster.particles.size());
  local.rows.reserve(cluster.rows.size());
  local.global_rows.reserve(cluster.rows.size());
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
}

}  // namespace deli
