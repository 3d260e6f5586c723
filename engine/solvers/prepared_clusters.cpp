#include "solvers/prepared_clusters.hpp"

namespace deli {

void EqualityClusters::prepare(const std::vector<Constraint>& equalities,
                               const std::vector<double>& mass) {
  particles_ = mass.size();
  held_particles_ = 0;
  clusters_.clear();
  cluster_from_first_particle_.assign(mass.size(), -1);
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
    cluster_from_first_particle_[clusters_[k].cluster.particles.front()] =
        static_cast<std::int32_t>(k);
  }
}

const PreparedCluster* EqualityClusters::find(const Cluster& cluster,
                                              const std::vector<Constraint>& rows) const {
  const std::int32_t first = cluster.particles.front();
  if (static_cast<std::size_t>(first) >= cluster_from_first_particle_.size()) return nullptr;
  const std::int32_t k = cluster_from_first_particle_[first];
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
