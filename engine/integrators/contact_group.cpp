#include "integrators/contact_group.hpp"

#include <Eigen/Eigenvalues>

#include "constraints/clusters.hpp"

namespace deli {

std::vector<char> contact_group(const std::vector<Constraint>& touched,
                                const std::vector<Constraint>& rods, std::size_t particle_count) {
  std::vector<char> group(particle_count, 0);
  for (const Constraint& c : touched) {
    group[static_cast<std::size_t>(c.i)] = 1;
    if (c.j >= 0) group[static_cast<std::size_t>(c.j)] = 1;
  }
  if (rods.empty()) return group;
  for (const Cluster& cluster : find_clusters(rods, particle_count)) {
    bool touching = false;
    for (std::int32_t i : cluster.particles)
      touching = touching || group[static_cast<std::size_t>(i)];
    if (!touching) continue;
    for (std::int32_t i : cluster.particles) group[static_cast<std::size_t>(i)] = 1;
  }
  return group;
}

std::vector<Vec3> internal_momenta(const Particles& particles, const Box& box,
                                   const std::vector<Vec3>& p, const std::vector<char>& group) {
  const std::size_t n = particles.size();
  const std::vector<double>& mass = particles.mass;
  const std::vector<Vec3>& x = particles.position;
  double total = 0;
  Vec3 momentum, centre;
  for (std::size_t i = 0; i < n; ++i) {
    if (!group[i]) continue;
    total += mass[i];
    momentum += p[i];
    centre += x[i] * mass[i];
  }
  std::vector<Vec3> d(n);
  if (!(total > 0)) return d;
  const Vec3 velocity = momentum * (1.0 / total);
  centre = centre * (1.0 / total);
  Vec3 omega;
  const auto& periodic = box.periodic();
  if (!periodic[0] && !periodic[1] && !periodic[2]) {
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    Eigen::Vector3d angular = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      if (!group[i]) continue;
      const Vec3 r = x[i] - centre;
      const Vec3 l = cross(r, p[i]);
      angular += Eigen::Vector3d(l.x, l.y, l.z);
      const Eigen::Vector3d e(r.x, r.y, r.z);
      inertia += mass[i] * (e.squaredNorm() * Eigen::Matrix3d::Identity() - e * e.transpose());
    }
    // Pseudo-inverse: a collinear group has no inertia about its line, and no angular
    // momentum along it either.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(inertia);
    const Eigen::Vector3d values = eigen.eigenvalues();
    const double floor = 1e-12 * values.cwiseAbs().maxCoeff();
    Eigen::Vector3d inverse = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) inverse[k] = values[k] > floor ? 1.0 / values[k] : 0.0;
    const Eigen::Vector3d w = eigen.eigenvectors() *
                              (inverse.asDiagonal() * (eigen.eigenvectors().transpose() * angular));
    omega = Vec3{w[0], w[1], w[2]};
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (group[i]) d[i] = p[i] - (velocity + cross(omega, x[i] - centre)) * mass[i];
  }
  return d;
}

}  // namespace deli
