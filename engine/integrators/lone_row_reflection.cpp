#include "integrators/lone_row_reflection.hpp"

namespace deli {

namespace {
// The row's normal velocity grad g . M^-1 p, with wi and wj its particles' inverse masses.
double normal_velocity_of(const Constraint& row, const Vec3& u, double wi, double wj,
                          const Vec3* p) {
  double v = wi * dot(u, p[row.i]);
  if (row.j >= 0) v -= wj * dot(u, p[row.j]);
  return v;
}
}  // namespace

double reflect_lone_row(const Constraint& row, const Vec3* x, const Box& box,
                        const std::vector<double>& mass, double tolerance, Vec3* p,
                        bool* left_approaching) {
  const Vec3 u = evaluate(row, x, box).u;
  const double wi = 1.0 / mass[row.i];
  const double wj = row.j >= 0 ? 1.0 / mass[row.j] : 0.0;
  const double stiffness = (wi + wj) * norm2(u);
  if (!(stiffness > 0.0)) return -1.0;
  const double normal_velocity = normal_velocity_of(row, u, wi, wj, p);
  if (left_approaching) *left_approaching = false;
  if (!(normal_velocity < -tolerance)) return 0.0;
  const double lambda = -2.0 * normal_velocity / stiffness;
  p[row.i] += u * lambda;
  if (row.j >= 0) p[row.j] -= u * lambda;
  // A second call's test: the same direction and masses, the new momenta.
  if (left_approaching) *left_approaching = normal_velocity_of(row, u, wi, wj, p) < -tolerance;
  return lambda;
}

}  // namespace deli
