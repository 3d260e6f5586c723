#include "integrators/lone_row_reflection.hpp"

namespace deli {

double reflect_lone_row(const Constraint& row, const Vec3* x, const Box& box,
                        const std::vector<double>& mass, double tolerance, Vec3* p) {
  const Vec3 u = evaluate(row, x, box).u;
  const double wi = 1.0 / mass[row.i];
  const double wj = row.j >= 0 ? 1.0 / mass[row.j] : 0.0;
  const double stiffness = (wi + wj) * norm2(u);
  if (!(stiffness > 0.0)) return -1.0;
  double normal_velocity = wi * dot(u, p[row.i]);
  if (row.j >= 0) normal_velocity -= wj * dot(u, p[row.j]);
  if (!(normal_velocity < -tolerance)) return 0.0;
  const double lambda = -2.0 * normal_velocity / stiffness;
  p[row.i] += u * lambda;
  if (row.j >= 0) p[row.j] -= u * lambda;
  return lambda;
}

}  // namespace deli
