#include "constraints/constraint.hpp"

namespace deli {

const char* kind_name(ConstraintKind k) {
  switch (k) {
    case ConstraintKind::rod:
      return "rod";
    case ConstraintKind::anchor:
      return "anchor";
    case ConstraintKind::sphere_pair:
      return "sphere pair";
    case ConstraintKind::plane:
      return "plane";
    case ConstraintKind::inside_sphere:
      return "inside sphere";
    case ConstraintKind::outside_sphere:
      return "outside sphere";
    case ConstraintKind::linear_pair:
      return "linearised pair";
  }
  return "?";
}

bool same_row(const Constraint& a, const Constraint& b) {
  return a.kind == b.kind && a.i == b.i && a.j == b.j && a.point.x == b.point.x &&
         a.point.y == b.point.y && a.point.z == b.point.z && a.normal.x == b.normal.x &&
         a.normal.y == b.normal.y && a.normal.z == b.normal.z && a.length == b.length;
}

Constraint linearized(const Constraint& c, const Vec3* q, const Box& box) {
  const ConstraintValue v = evaluate(c, q, box);
  Constraint l = c;
  l.normal = v.u;
  if (c.j >= 0) {
    l.kind = ConstraintKind::linear_pair;
    l.length = dot(v.u, box.minimum_image(q[c.i] - q[c.j])) - v.gap;
  } else {
    l.kind = ConstraintKind::plane;
    l.point = q[c.i] - v.u * v.gap;
    l.length = 0.0;
  }
  return l;
}

}  // namespace deli
