#pragma once

#include <memory>
#include <vector>

#include "constraints/clusters.hpp"
#include "solvers/cluster_rows.hpp"
#include "solvers/rod_chain.hpp"

namespace deli {

// A cluster in its own numbering with its row structure, ready for the solvers.
struct PreparedCluster {
  Cluster cluster;
  LocalCluster local;
  std::unique_ptr<ClusterRows> structure;  // refers to `local`
  std::unique_ptr<RodChain> chain;         // its chain form, when it is a chain of rods
};

// The clusters of the fixed equality rows (a molecule's rods, a pendulum's strings),
// clustered and localised once per run instead of at every solve: a step whose rows are
// these equalities, or these plus inequalities that leave some of their clusters untouched,
// reuses them.
class EqualityClusters {
 public:
  void prepare(const std::vector<Constraint>& equalities, const std::vector<double>& mass);
  bool prepared_for(std::size_t particle_count) const { return particles_ == particle_count; }
  // Whether every particle is in one of the clusters (a melt of rigid chains).
  bool hold_every_particle() const { return held_particles_ == particles_; }
  // In find_clusters' order.
  const std::vector<PreparedCluster>& all() const { return clusters_; }
  // The prepared cluster with the same particles and, row for row, the same constraints as
  // `cluster` (rows indexing `rows`); null if none.
  const PreparedCluster* find(const Cluster& cluster, const std::vector<Constraint>& rows) const;
  // The clusters of `rows` (the equality rows prepare() was given, then other rows from index
  // `first` = their count on) that hold one of the others: find_clusters(rows) without the
  // clusters of equality rows alone, the same particles and rows in the same order. Found
  // from the other rows alone, each of their particles standing for its equality cluster
  // (the reflections' few contacts, not the 1170 rods of the default input, clustered).
  std::vector<Cluster> clusters_holding(const std::vector<Constraint>& rows,
                                        std::size_t first) const;

 private:
  std::vector<PreparedCluster> clusters_;
  std::vector<std::int32_t> cluster_of_particle_;  // -1: in no cluster
  std::size_t rows_ = 0;                           // equality rows prepared
  std::size_t particles_ = static_cast<std::size_t>(-1);
  std::size_t held_particles_ = 0;  // in the clusters (disjoint)
};

}  // namespace deli
