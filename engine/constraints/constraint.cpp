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

namespace {
// Distance and unit direction of d; a zero vector has no direction: u = 0 then, which the
// solvers see as a singular row and report rather than divide by zero.
ConstraintValue distance(const Vec3& d, double length) {
  const double r = norm(d);
  return {r - length, r > 0 ? d * (1.0 / r) : Vec3{}};
}
}  // namespace

ConstraintValue evaluate(const Constraint& c, const Vec3* x, const Box& box) {
  switch (c.kind) {
    case ConstraintKind::rod:
    case ConstraintKind::sphere_pair:
      return distance(box.minimum_image(x[c.i] - x[c.j]), c.length);
    case ConstraintKind::anchor:
      return distance(x[c.i] - c.point, c.length);
    case ConstraintKind::plane:
      return {dot(c.normal, x[c.i] - c.point) - c.length, c.normal};
    case ConstraintKind::inside_sphere: {
      const ConstraintValue v = distance(x[c.i] - c.point, 0.0);
      return {c.length - v.gap, -v.u};
    }
    case ConstraintKind::outside_sphere:
      return distance(x[c.i] - c.point, c.length);
    case ConstraintKind::linear_pair:
      return {dot(c.normal, box.minimum_image(x[c.i] - x[c.j])) - c.length, c.normal};
  }
  return {0, {}};
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
