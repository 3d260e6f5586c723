#pragma once

#include "constraints/constraint.hpp"

namespace deli::testing {

// A two-particle row (rod, sphere pair, ...) of the given length.
inline Constraint pair_row(ConstraintKind kind, int i, int j, double length) {
  Constraint c{kind};
  c.i = i;
  c.j = j;
  c.length = length;
  return c;
}

// A plane wall row of one particle.
inline Constraint plane_row(int i, Vec3 point, Vec3 normal) {
  Constraint c{ConstraintKind::plane};
  c.i = i;
  c.point = point;
  c.normal = normal;
  return c;
}

}  // namespace deli::testing
