#include "solvers/prepared_clusters.hpp"

#include <algorithm>
#include <stdexcept>

namespace deli {

void EqualityClusters::prepare(const std::vector<Constraint>& equalities,
                               const std::vector<double>& mass) {
  particles_ = mass.size();
  rows_ = equalities.size();
  held_particles_ = 0;
  clusters_.clear();
  cluster_of_particle_.assign(mass.size(), -1);
  for (Cluster& cluster : find_clusters(equalities, mass.size())) {
    PreparedCluster& prepared = clusters_.emplace_back();
    prepared.local = localize(cluster, equalities, mass);
    held_particles_ += cluster.particles.size();
    prepared.cluster = std::move(cluster);
  }
  // The structures refer to their clusters: made once the vector no longer moves.
  for (std::size_t k = 0; k < clusters_.size(); ++k) {
    clusters_[k].structure = std::make_unique<ClusterRows>(clusters_[k].local);
    if (clusters_[k].structure->tridiagonal())
      clusters_[k].chain = RodChain::make(clusters_[k].local);
    for (const std::int32_t p : clusters_[k].cluster.particles) {
      cluster_of_particle_[p] = static_cast<std::int32_t>(k);
    }
  }
}

// A cluster's particles are ascending: its first is its smallest, and stands for it. The
// components of the other rows over the stand-ins are the clusters sought, and a component's
// smallest stand-in is its cluster's smallest particle, so find_clusters orders them as it
// orders the whole rows' clusters.
std::vector<Cluster> EqualityClusters::clusters_holding(const std::vector<Constraint>& rows,
                                                        std::size_t first) const {
  if (first != rows_) {
    throw std::logic_error("clusters_holding: the rows do not start with the prepared equalities");
  }
  auto stand_in = [&](std::int32_t p) {
    const std::int32_t k = cluster_of_particle_[static_cast<std::size_t>(p)];
    return k < 0 ? p : clusters_[static_cast<std::size_t>(k)].cluster.particles.front();
  };
  std::vector<Constraint> others(rows.begin() + static_cast<std::ptrdiff_t>(first), rows.end());
  for (Constraint& c : others) {
    c.i = stand_in(c.i);
    if (c.j >= 0) c.j = stand_in(c.j);
  }
  std::vector<Cluster> found = find_clusters(others, particles_);
  for (Cluster& cluster : found) {
    std::vector<std::int32_t> particles, held_rows;
    for (const std::int32_t s : cluster.particles) {
      // A stand-in in a cluster is that cluster's first particle.
      const std::int32_t k = cluster_of_particle_[static_cast<std::size_t>(s)];
      if (k < 0) {
        particles.push_back(s);
        continue;
      }
      const Cluster& held = clusters_[static_cast<std::size_t>(k)].cluster;
      particles.insert(particles.end(), held.particles.begin(), held.particles.end());
      held_rows.insert(held_rows.end(), held.rows.begin(), held.rows.end());
    }
    std::sort(particles.begin(), particles.end());
    std::sort(held_rows.begin(), held_rows.end());
    for (const std::int32_t r : cluster.rows) {
      held_rows.push_back(static_cast<std::int32_t>(first) + r);
    }
    cluster.particles = std::move(particles);
    cluster.rows = std::move(held_rows);
  }
  return found;
}

const PreparedCluster* EqualityClusters::find(const Cluster& cluster,
                                              const std::vector<Constraint>& rows) const {
  const std::int32_t first = cluster.particles.front();
  if (static_cast<std::size_t>(first) >= cluster_of_particle_.size()) return nullptr;
  const std::int32_t k = cluster_of_particle_[first];
  if (k < 0) return nullptr;
  const PreparedCluster& prepared = clusters_[k];
  if (prepared.cluster.particles != cluster.particles ||
      prepared.local.rows.size() != cluster.rows.size()) {
    return nullptr;
  }
  // Same rows in the same order (local rows hold local indices: compare with the originals'
  // global indices restored).
  for (std::size_t r = 0; r < cluster.rows.size(); ++r) {
    Constraint local = prepared.local.rows[r];
    local.i = prepared.local.particles[local.i];
    if (local.j >= 0) local.j = prepared.local.particles[local.j];
    if (!same_row(local, rows[cluster.rows[r]])) return nullptr;
  }
  return &prepared;
}

}  // namespace deli
