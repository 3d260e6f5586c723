#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec3.hpp"
#include "system/particles.hpp"

namespace deli {

// What acts on the system from outside, as far as it breaks the symmetries whose momenta
// the dynamics conserves. A plane wall or a uniform field along n breaks translations
// along n and leaves only rotations about axes parallel to n; a sphere wall, an anchor
// (pendulum string) or a radial field centred at c breaks every translation and leaves
// only rotations about axes through c; a periodic axis e leaves translations and only
// rotations about axes parallel to e; a heat bath that acts on each particle on its own
// (Langevin) conserves nothing.
struct ExternalActions {
  std::vector<Vec3> directions;  // plane normals, uniform field directions
  std::vector<Vec3> centres;     // sphere walls, anchor points, radial field centres
  std::array<bool, 3> periodic{true, true, true};
  bool bath_on_each_particle = false;
};

// The degrees of freedom of the momenta: 3N, less one per equality constraint (rod or
// anchor; contacts remove none: they hold only while touching), less one per conserved
// component of the total linear and angular momentum (LAMMPS counts 3N - 3 - constraints,
// OpenMM 3N - constraints - 3 with its motion remover; neither checks what is conserved).
struct DegreesOfFreedom {
  std::int64_t particles = 0;
  std::int64_t constraints = 0;
  int translations = 3;  // conserved linear momentum components
  int rotations = 0;     // conserved angular momentum components
  Vec3 rotation_centre;  // where `rotations` > 0: the point the axes pass through
  std::vector<Vec3> translation_axes, rotation_axes;  // orthonormal

  double count() const;
  // "3N - rods - translations - rotations = ..." for the run's header.
  std::string describe() const;
  // What a system of n particles without constraints, periodic in every direction, has
  // (3N - 3): tests and tools that give no count.
  static DegreesOfFreedom periodic_unconstrained(std::size_t n);
};

// `particles` gives masses and the starting positions, whose inertia decides how many
// rotations a configuration has (a single particle or a straight chain has fewer than 3).
DegreesOfFreedom count_degrees_of_freedom(const Particles& particles, std::size_t constraints,
                                          const ExternalActions& actions);

// Removes the conserved components of linear and angular momentum from the velocities
// (rigid motions: they keep rods and contacts as they are).
void remove_conserved_momenta(Particles& particles, const DegreesOfFreedom& dof);
// Removes the conserved momenta, then scales the velocities to `temperature` with the
// count's degrees of freedom.
void set_temperature(Particles& particles, const DegreesOfFreedom& dof, double temperature);

}  // namespace deli
