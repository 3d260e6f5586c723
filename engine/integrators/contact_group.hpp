#pragma once

#include <vector>

#include "constraints/constraint.hpp"
#include "system/box.hpp"
#include "system/particles.hpp"

namespace deli {

// The particles a contact step's energy restoration may act on: those of the rows that
// touched, with every rod cluster one of them belongs to (1 = in the group).
std::vector<char> contact_group(const std::vector<Constraint>& touched,
                                const std::vector<Constraint>& rods, std::size_t particle_count);

// The group's momenta less its rigid motion: p_i - m_i (V + omega x (x_i - R)) for the members
// (zero for the others), V, R its centre of mass's velocity and position and omega = I^-1 L its
// angular velocity about R (the pseudo-inverse where the group is collinear). An impulse along
// it keeps the group's linear and angular momentum (about any point) and, rigid motion keeping
// every distance, stays tangent to its rods. Where an axis is periodic (no angular momentum
// to keep, and the members' positions may be wrapped) the translation alone is taken out.
std::vector<Vec3> internal_momenta(const Particles& particles, const Box& box,
                                   const std::vector<Vec3>& p, const std::vector<char>& group);

}  // namespace deli
