#pragma once

#include <cstdint>
#include <vector>

#include "constraints/constraint.hpp"

namespace deli {

// Constraints couple particles only through shared particles: each connected component
// (one chain's rods, a group of touching spheres, a chain and the contacts on it) is
// solved on its own. Clusters come ordered by their smallest particle index, particles
// ascending, rows in the order given: deterministic.
struct Cluster {
  std::vector<std::int32_t> particles;  // global indices, ascending
  std::vector<std::int32_t> rows;       // indices into the row list
};
std::vector<Cluster> find_clusters(const std::vector<Constraint>& rows, std::size_t particle_count);
// The same clusters into `out`, whose lists keep their storage between calls (a hard-sphere
// fluid clusters its shared contacts several times a step).
void find_clusters(const std::vector<Constraint>& rows, std::size_t particle_count,
                   std::vector<Cluster>& out);

// A cluster in its own numbering: particles 0..n-1, rows with local i, j.
struct LocalCluster {
  std::vector<std::int32_t> particles;  // local -> global
  std::vector<Constraint> rows;
  std::vector<std::int32_t> global_rows;  // local row -> index in the step's row list
  std::vector<double> inverse_mass;
  std::size_t size() const { return particles.size(); }
};
LocalCluster localize(const Cluster& cluster, const std::vector<Constraint>& rows,
                      const std::vector<double>& mass);
// The same into `out`, its lists keeping their storage.
void localize(const Cluster& cluster, const std::vector<Constraint>& rows,
              const std::vector<double>& mass, LocalCluster& out);

}  // namespace deli
