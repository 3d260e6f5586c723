#include "simulation/degrees_of_freedom.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

namespace deli {

namespace {

Eigen::Vector3d eigen(const Vec3& v) {
  return {v.x, v.y, v.z};
}
Vec3 vec3(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// Unit vectors of `directions` that are not zero.
std::vector<Eigen::Vector3d> unit(const std::vector<Vec3>& directions) {
  std::vector<Eigen::Vector3d> out;
  for (const Vec3& d : directions) {
    const Eigen::Vector3d e = eigen(d);
    if (e.norm() > 0) out.push_back(e.normalized());
  }
  return out;
}

bool parallel(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.cross(b).norm() <= 1e-9;
}

Eigen::Matrix3d inertia_about(const Particles& p, const Eigen::Vector3d& centre) {
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d r = eigen(p.position[i]) - centre;
    inertia += p.mass[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  return inertia;
}

Eigen::Vector3d centre_of_mass(const Particles& p) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double mass = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    sum += p.mass[i] * eigen(p.position[i]);
    mass += p.mass[i];
  }
  return mass > 0 ? Eigen::Vector3d(sum / mass) : Eigen::Vector3d::Zero();
}

}  // namespace

double DegreesOfFreedom::count() const {
  return 3.0 * static_cast<double>(particles) - static_cast<double>(constraints) - translations -
         rotations;
}

std::string DegreesOfFreedom::describe() const {
  std::ostringstream s;
  s << "degrees of freedom " << count() << " = 3 x " << particles << " atoms";
  if (constraints > 0) s << " - " << constraints << " rods/strings";
  s << " - " << translations << " conserved momentum components";
  if (rotations > 0) s << " - " << rotations << " conserved angular momentum components";
  return s.str();
}

DegreesOfFreedom DegreesOfFreedom::periodic_unconstrained(std::size_t n) {
  DegreesOfFreedom dof;
  dof.particles = static_cast<std::int64_t>(n);
  dof.translation_axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  return dof;
}

DegreesOfFreedom count_degrees_of_freedom(const Particles& particles, std::size_t constraints,
                                          const ExternalActions& actions) {
  DegreesOfFreedom dof;
  dof.particles = static_cast<std::int64_t>(particles.size());
  dof.constraints = static_cast<std::int64_t>(constraints);
  dof.translations = 0;
  if (actions.bath_on_each_particle || particles.size() == 0) return dof;
  const std::vector<Eigen::Vector3d> directions = unit(actions.directions);

  // Translations: the directions orthogonal to every breaking direction, none with a centre.
  if (actions.centres.empty()) {
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& d : directions) spread += d * d.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(spread);
    for (int k = 0; k < 3; ++k) {
      if (solver.eigenvalues()(k) <= 1e-9)
        dof.translation_axes.push_back(vec3(solver.eigenvectors().col(k)));
    }
    dof.translations = static_cast<int>(dof.translation_axes.size());
  }

  // Rotations: axes parallel to every direction and periodic axis, through every centre.
  std::vector<Eigen::Vector3d> axis_must_parallel = directions;
  for (int a = 0; a < 3; ++a) {
    if (actions.periodic[a]) axis_must_parallel.push_back(Eigen::Vector3d::Unit(a));
  }
  std::vector<Eigen::Vector3d> centres;
  for (const Vec3& c : actions.centres) {
    bool seen = false;
    for (const Eigen::Vector3d& k : centres) seen = seen || (k - eigen(c)).norm() <= 1e-9;
    if (!seen) centres.push_back(eigen(c));
  }
  // Centres on one line fix the axis to that line.
  if (centres.size() >= 2) {
    const Eigen::Vector3d line = (centres[1] - centres[0]).normalized();
    for (const Eigen::Vector3d& c : centres) {
      if ((c - centres[0]).cross(line).norm() > 1e-9) return dof;
    }
    axis_must_parallel.push_back(line);
  }
  std::vector<Eigen::Vector3d> allowed;  // empty: any direction
  for (const Eigen::Vector3d& d : axis_must_parallel) {
    if (!parallel(d, axis_must_parallel.front())) return dof;
  }
  if (!axis_must_parallel.empty()) allowed.push_back(axis_must_parallel.front());

  const Eigen::Vector3d centre = centres.empty() ? centre_of_mass(particles) : centres.front();
  const Eigen::Matrix3d inertia = inertia_about(particles, centre);
  const double scale = inertia.trace();
  if (!(scale > 0)) return dof;
  if (allowed.empty()) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
    for (int k = 0; k < 3; ++k) {
      if (solver.eigenvalues()(k) > 1e-10 * scale)
        dof.rotation_axes.push_back(vec3(solver.eigenvectors().col(k)));
    }
  } else if (allowed.front().dot(inertia * allowed.front()) > 1e-10 * scale) {
    dof.rotation_axes.push_back(vec3(allowed.front()));
  }
  dof.rotations = static_cast<int>(dof.rotation_axes.size());
  dof.rotation_centre = vec3(centre);
  return dof;
}

void remove_conserved_momenta(Particles& p, const DegreesOfFreedom& dof) {
  const std::size_t n = p.size();
  double mass = 0.0;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mass += p.mass[i];
    momentum += p.mass[i] * eigen(p.velocity[i]);
  }
  for (const Vec3& axis : dof.translation_axes) {
    const Vec3 drift = axis * (dot(axis, vec3(momentum)) / mass);
    for (Vec3& v : p.velocity) v -= drift;
  }
  if (dof.rotations > 0) {
    // The rigid rotation omega (in the span of the conserved axes) carrying the conserved
    // angular momentum components: (a_k . I a_l) w_l = a_k . L.
    const Eigen::Vector3d centre = eigen(dof.rotation_centre);
    const Eigen::Matrix3d inertia = inertia_about(p, centre);
    Eigen::Vector3d angular = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      angular += p.mass[i] * (eigen(p.position[i]) - centre).cross(eigen(p.velocity[i]));
    }
    const auto k = static_cast<Eigen::Index>(dof.rotation_axes.size());
    Eigen::MatrixXd axes(3, k);
    for (Eigen::Index a = 0; a < k; ++a) axes.col(a) = eigen(dof.rotation_axes[a]);
    const Eigen::MatrixXd reduced = axes.transpose() * inertia * axes;
    const Eigen::VectorXd w = reduced.ldlt().solve(axes.transpose() * angular);
    const Eigen::Vector3d omega = axes * w;
    for (std::size_t i = 0; i < n; ++i) {
      p.velocity[i] -= vec3(omega.cross(eigen(p.position[i]) - centre));
    }
  }
}

void set_temperature(Particles& p, const DegreesOfFreedom& dof, double temperature) {
  remove_conserved_momenta(p, dof);
  const std::size_t n = p.size();
  double twice_kinetic = 0.0;
  for (std::size_t i = 0; i < n; ++i) twice_kinetic += p.mass[i] * norm2(p.velocity[i]);
  if (!(twice_kinetic > 0.0) || dof.count() <= 0) return;
  const double scale = std::sqrt(temperature * dof.count() / twice_kinetic);
  for (Vec3& v : p.velocity) v *= scale;
}

}  // namespace deli
