#include "solvers/position_update.hpp"

#include <cmath>

#include "solvers/cluster_matrices.hpp"

namespace deli {

namespace {
double fischer_burmeister(double a, double b) {
  return a + b - std::sqrt(a * a + b * b);
}
}  // namespace

PositionUpdate solve_position_update(const LocalCluster& cluster, const std::vector<bool>& equality,
                                     const std::vector<Vec3>& q, const std::vector<Vec3>& x0,
                                     double h, const Box& box, double tolerance,
                                     int max_iterations) {
  const auto m = static_cast<Eigen::Index>(cluster.rows.size());
  std::vector<int> all(static_cast<std::size_t>(m));
  for (Eigen::Index k = 0; k < m; ++k) all[k] = static_cast<int>(k);
  const Eigen::VectorXd w = inverse_mass_diagonal(cluster);
  // Directions of the impulses: gradients at the start of the step, fixed.
  const Eigen::MatrixXd Cq = gradient_matrix(cluster, all, q, box);
  const Eigen::MatrixXd Wc = w.asDiagonal() * Cq * h;
  const Eigen::VectorXd x0_flat = flatten(x0);

  PositionUpdate out;
  out.z = Eigen::VectorXd::Zero(m);
  auto positions = [&](const Eigen::VectorXd& z) { return unflatten(x0_flat + Wc * z); };
  auto residual = [&](const Eigen::VectorXd& z, const std::vector<Vec3>& x, Eigen::VectorXd& gaps) {
    Eigen::VectorXd phi(m);
    gaps.resize(m);
    for (Eigen::Index k = 0; k < m; ++k) {
      gaps(k) = evaluate(cluster.rows[k], x.data(), box).gap;
      phi(k) = equality[k] ? gaps(k) : fischer_burmeister(z(k), gaps(k));
    }
    return phi;
  };

  std::vector<Vec3> x = positions(out.z);
  Eigen::VectorXd gaps;
  Eigen::VectorXd phi = residual(out.z, x, gaps);
  for (;;) {
    out.status.residual = phi.lpNorm<Eigen::Infinity>();
    if (out.status.residual <= tolerance) {
      out.status.converged = true;
      break;
    }
    if (out.status.iterations >= max_iterations) break;
    ++out.status.iterations;
    // d gap_k / d z = grad g_k(x)^T h M^-1 C(q).
    const Eigen::MatrixXd dgap = gradient_matrix(cluster, all, x, box).transpose() * Wc;
    Eigen::MatrixXd J = dgap;
    for (Eigen::Index k = 0; k < m; ++k) {
      if (equality[k]) continue;
      const double a = out.z(k), b = gaps(k), r = std::sqrt(a * a + b * b);
      // At (0, 0) any element of the generalized Jacobian will do; take the direction (1, 1).
      const double da = r > 0 ? 1 - a / r : 1 - M_SQRT1_2;
      const double db = r > 0 ? 1 - b / r : 1 - M_SQRT1_2;
      J.row(k) = db * dgap.row(k);
      J(k, k) += da;
    }
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-phi);
    const double merit = phi.squaredNorm();
    double t = 1.0;
    for (;;) {
      const Eigen::VectorXd trial = out.z + t * step;
      const std::vector<Vec3> xt = positions(trial);
      Eigen::VectorXd gt;
      const Eigen::VectorXd pt = residual(trial, xt, gt);
      if (pt.squaredNorm() <= (1 - 1e-4 * t) * merit || t < 1e-10) {
        out.z = trial, x = xt, gaps = gt, phi = pt;
        break;
      }
      t *= 0.5;
    }
  }
  out.x = std::move(x);
  out.impulse = unflatten(Cq * out.z);
  return out;
}

}  // namespace deli
