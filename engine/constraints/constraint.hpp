#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "core/vec3.hpp"
#include "system/box.hpp"

namespace deli {

// The contract every constraint meets (Chrono/Siconos style): a kind, one or two
// particles, a gap (residual) and its gradient. Every deli constraint's gradient is +u on
// particle i and, for two-particle kinds, -u on particle j, so a row is (i, j, u).
enum class ConstraintKind : std::uint8_t {
  rod,             // equality: |x_i - x_j| - length = 0
  anchor,          // equality: |x_i - point| - length = 0 (pendulum string)
  sphere_pair,     // inequality: |x_i - x_j| - (r_i + r_j) >= 0
  plane,           // inequality: n . (x_i - point) - r_i >= 0
  inside_sphere,   // inequality: R - r_i - |x_i - c| >= 0
  outside_sphere,  // inequality: |x_i - c| - R - r_i >= 0
  linear_pair      // inequality: n . (x_i - x_j) - length >= 0 (a pair linearised)
};

constexpr bool is_equality(ConstraintKind k) {
  return k == ConstraintKind::rod || k == ConstraintKind::anchor;
}
constexpr bool is_pair(ConstraintKind k) {
  return k == ConstraintKind::rod || k == ConstraintKind::sphere_pair ||
         k == ConstraintKind::linear_pair;
}
const char* kind_name(ConstraintKind k);

struct Constraint {
  ConstraintKind kind;
  std::int32_t i = -1, j = -1;  // j = -1 for one-particle kinds
  double length = 0;            // rod/anchor length, contact distance, R + r or R - r, r
  Vec3 point;                   // anchor point, plane point, sphere centre
  Vec3 normal;                  // plane unit normal
};

// Gap and gradient block u (on particle i; -u on j) at positions x.
struct ConstraintValue {
  double gap;
  Vec3 u;
};

// Inline: the candidate scans call it for thousands of rows per step.
inline ConstraintValue evaluate(const Constraint& c, const Vec3* x, const Box& box);

// evaluate(c, x, box).gap without the gradient (no division).
inline double gap_of(const Constraint& c, const Vec3* x, const Box& box) {
  if (c.kind == ConstraintKind::sphere_pair || c.kind == ConstraintKind::rod) {
    return norm(box.minimum_image(x[c.i] - x[c.j])) - c.length;
  }
  return evaluate(c, x, box).gap;
}

// The row's gap at x (gap_of's number) when it may be at most `limit`; +infinity when the
// squared distance of a sphere pair already puts it beyond by far more than rounding (no
// square root then). For the scans that only compare gaps with a limit or keep the smallest.
inline double gap_unless_beyond(const Constraint& c, const Vec3* x, const Box& box, double limit) {
  if (c.kind == ConstraintKind::sphere_pair && limit >= -0.5 * c.length) {
    const double d2 = norm2(box.minimum_image(x[c.i] - x[c.j]));
    const double within = c.length + limit;
    if (d2 > within * within * (1.0 + 1e-6)) return std::numeric_limits<double>::infinity();
    return std::sqrt(d2) - c.length;
  }
  return gap_of(c, x, box);
}

// The same constraint: kind, particles and every parameter equal.
bool same_row(const Constraint& a, const Constraint& b);

// The constraint's first-order expansion at positions q, as a constraint of its own: a
// plane for a one-particle row, a linear pair for a two-particle one. Its gap agrees at q
// and its gradient is the one at q, everywhere.
Constraint linearized(const Constraint& c, const Vec3* q, const Box& box);

namespace detail {
// Distance and unit direction of d; a zero vector has no direction: u = 0 then, which the
// solvers see as a singular row and report rather than divide by zero.
inline ConstraintValue distance(const Vec3& d, double length) {
  const double r = norm(d);
  return {r - length, r > 0 ? d * (1.0 / r) : Vec3{}};
}
}  // namespace detail

inline ConstraintValue evaluate(const Constraint& c, const Vec3* x, const Box& box) {
  switch (c.kind) {
    case ConstraintKind::rod:
    case ConstraintKind::sphere_pair:
      return detail::distance(box.minimum_image(x[c.i] - x[c.j]), c.length);
    case ConstraintKind::anchor:
      return detail::distance(x[c.i] - c.point, c.length);
    case ConstraintKind::plane:
      return {dot(c.normal, x[c.i] - c.point) - c.length, c.normal};
    case ConstraintKind::inside_sphere: {
      const ConstraintValue v = detail::distance(x[c.i] - c.point, 0.0);
      return {c.length - v.gap, -v.u};
    }
    case ConstraintKind::outside_sphere:
      return detail::distance(x[c.i] - c.point, c.length);
    case ConstraintKind::linear_pair:
      return {dot(c.normal, box.minimum_image(x[c.i] - x[c.j])) - c.length, c.normal};
  }
  return {0, {}};
}

}  // namespace deli
