#include "integrators/lone_row_reflection.hpp"

namespace deli {

namespace {
// The row's direction, inverse masses, stiffness and normal velocity.
struct LoneRow {
  Vec3 u;
  double wi, wj, stiffness, normal_velocity;
};
LoneRow lone_row(const Constraint& row, const Vec3* x, const Box& box,
                 const std::vector<double>& mass, const Vec3* p) {
  LoneRow r;
  r.u = evaluate(row, x, box).u;
  r.wi = 1.0 / mass[row.i];
  r.wj = row.j >= 0 ? 1.0 / mass[row.j] : 0.0;
  r.stiffness = (r.wi + r.wj) * norm2(r.u);
  r.normal_velocity = r.wi * dot(r.u, p[row.i]);
  if (row.j >= 0) r.normal_velocity -= r.wj * dot(r.u, p[row.j]);
  return r;
}
}  // namespace

bool lone_row_approaching(const Constraint& row, const Vec3* x, const Box& box,
                          const std::vector<double>& mass, double tolerance, const Vec3* p) {
  const LoneRow r = lone_row(row, x, box, mass, p);
  return r.stiffness > 0.0 && r.normal_velocity < -tolerance;
}

double reflect_lone_row(const Constraint& row, const Vec3* x, const Box& box,
                        const std::vector<double>& mass, double tolerance, Vec3* p) {
  const LoneRow r = lone_row(row, x, box, mass, p);
  const Vec3& u = r.u;
  const double stiffness = r.stiffness, normal_velocity = r.normal_velocity;
  if (!(stiffness > 0.0)) return -1.0;
  if (!(normal_velocity < -tolerance)) return 0.0;
  const double lambda = -2.0 * normal_velocity / stiffness;
  p[row.i] += u * lambda;
  if (row.j >= 0) p[row.j] -= u * lambda;
  return lambda;
}

}  // namespace deli
