#include "solvers/position_update.hpp"

#include <cmath>

#include "solvers/cluster_rows.hpp"

namespace deli {

namespace {
double fischer_burmeister(double a, double b) {
  return a + b - std::sqrt(a * a + b * b);
}

Eigen::VectorXd solve_linear(const Eigen::MatrixXd& J, const Eigen::VectorXd& rhs) {
  Eigen::VectorXd step = J.partialPivLu().solve(rhs);
  // Dependent rows (a rigid loop, a contact repeating a rod) make J singular: least norm.
  if (!step.allFinite()) step = J.completeOrthogonalDecomposition().solve(rhs);
  return step;
}
}  // namespace

PositionUpdate solve_position_update(const LocalCluster& cluster, const std::vector<bool>& equality,
                                     const std::vector<Vec3>& q, const std::vector<Vec3>& x0,
                                     double h, const Box& box, double tolerance,
                                     int max_iterations) {
  return solve_position_update(ClusterRows(cluster), equality, q, x0, h, box, tolerance,
                               max_iterations);
}

PositionUpdate solve_position_update(const ClusterRows& structure,
                                     const std::vector<bool>& equality, const std::vector<Vec3>& q,
                                     const std::vector<Vec3>& x0, double h, const Box& box,
                                     double tolerance, int max_iterations) {
  const LocalCluster& cluster = structure.cluster();
  const auto m = static_cast<Eigen::Index>(cluster.rows.size());
  const std::size_t n = cluster.size();
  // Directions of the impulses: gradients at the start of the step, fixed.
  const std::vector<Vec3> uq = structure.directions(q, box);
  // Rods only, numbered along a chain: the Newton matrix is tridiagonal.
  bool banded = structure.tridiagonal();
  for (Eigen::Index k = 0; banded && k < m; ++k) banded = equality[k];

  PositionUpdate out;
  out.z = Eigen::VectorXd::Zero(m);
  std::vector<Vec3> j(n);
  auto positions = [&](const Eigen::VectorXd& z, std::vector<Vec3>& x) {
    structure.impulse_into(uq, z, j);
    x.resize(n);
    for (std::size_t p = 0; p < n; ++p) x[p] = x0[p] + j[p] * (h * cluster.inverse_mass[p]);
  };
  auto residual = [&](const Eigen::VectorXd& z, const std::vector<Vec3>& x, Eigen::VectorXd& gaps,
                      Eigen::VectorXd& phi) {
    phi.resize(m);
    gaps.resize(m);
    for (Eigen::Index k = 0; k < m; ++k) {
      gaps(k) = evaluate(cluster.rows[k], x.data(), box).gap;
      phi(k) = equality[k] ? gaps(k) : fischer_burmeister(z(k), gaps(k));
    }
  };

  std::vector<Vec3> x, xt;
  positions(out.z, x);
  Eigen::VectorXd gaps, phi, gt, pt, trial, step;
  residual(out.z, x, gaps, phi);
  Tridiagonal bands;
  for (;;) {
    out.status.residual = phi.lpNorm<Eigen::Infinity>();
    if (out.status.residual <= tolerance) {
      out.status.converged = true;
      break;
    }
    if (out.status.iterations >= max_iterations) break;
    ++out.status.iterations;
    // d gap_k / d z_l = h grad g_k(x)^T M^-1 C_l(q).
    bool solved = false;
    if (banded) {
      structure.coupling_bands(structure.directions(x, box), uq, bands);
      bands.lower *= h;
      bands.diagonal *= h;
      bands.upper *= h;
      solved = solve_tridiagonal(bands, -phi, step);
    }
    if (!solved) {
      const Eigen::MatrixXd dgap = h * structure.coupling(structure.directions(x, box), uq);
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
      step = solve_linear(J, -phi);
    }
    const double merit = phi.squaredNorm();
    double t = 1.0;
    for (;;) {
      trial = out.z + t * step;
      positions(trial, xt);
      residual(trial, xt, gt, pt);
      if (pt.squaredNorm() <= (1 - 1e-4 * t) * merit || t < 1e-10) {
        std::swap(out.z, trial);
        std::swap(x, xt);
        std::swap(gaps, gt);
        std::swap(phi, pt);
        break;
      }
      t *= 0.5;
    }
  }
  out.x = std::move(x);
  out.impulse = structure.impulse(uq, out.z);
  return out;
}

}  // namespace deli
