#include "solvers/position_update.hpp"

#include <cmath>

#include "solvers/cluster_rows.hpp"
#include "solvers/least_norm.hpp"

namespace deli {

namespace {
double fischer_burmeister(double a, double b) {
  return a + b - std::sqrt(a * a + b * b);
}

// Dependent rows (a rigid loop, a contact repeating a rod) make J singular, and nearly
// dependent ones (the loop slightly bent, the contact nearly along the rod) nearly so: LU
// then gives a huge finite step along the near-null direction. Below this reciprocal
// condition number the directions whose pivots fall under it (relative to the largest) are
// dropped and the step is the least-norm solution of the rest (the threshold of the
// tridiagonal solver's vanishing pivots).
constexpr double kDependentRows = 1e-12;

Eigen::VectorXd solve_linear(const Eigen::MatrixXd& J, const Eigen::VectorXd& rhs) {
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(J);
  Eigen::VectorXd step = lu.solve(rhs);
  if (!step.allFinite() || !(lu.rcond() > kDependentRows)) {
    LeastNorm least_norm;
    least_norm.compute(J, kDependentRows);
    least_norm.solve(rhs, step);
  }
  return step;
}
}  // namespace

PositionUpdate solve_position_update(const LocalCluster& cluster, const std::vector<bool>& equality,
                                     const std::vector<Vec3>& q, const std::vector<Vec3>& x0,
                                     double h, const Box& box, double tolerance, int newton_limit,
                                     int line_search_limit) {
  return solve_position_update(ClusterRows(cluster), equality, q, x0, h, box, tolerance,
                               newton_limit, line_search_limit);
}

PositionUpdate solve_position_update(const ClusterRows& structure,
                                     const std::vector<bool>& equality, const std::vector<Vec3>& q,
                                     const std::vector<Vec3>& x0, double h, const Box& box,
                                     double tolerance, int newton_limit, int line_search_limit) {
  const LocalCluster& cluster = structure.cluster();
  const auto m = static_cast<Eigen::Index>(cluster.rows.size());
  const std::size_t n = cluster.size();
  // Directions of the impulses: gradients at the start of the step, fixed.
  const std::vector<Vec3> uq = structure.directions(q, box);
  // Rods only, numbered along a chain: the Newton matrix is tridiagonal.
  bool banded = structure.tridiagonal();
  for (Eigen::Index k = 0; banded && k < m; ++k) banded = equality[k];

  // Complementarity pairs an impulse z_k with a gap g_k (sigma): Fischer-Burmeister is
  // taken of (s_k z_k, g_k), s_k = h (w_i + w_j) being how far the row's own impulse moves
  // its gap per unit (the diagonal of d gap / d z), so both arguments are lengths and the
  // residual tolerance means the same for a heavy pair and a light one, at any timestep.
  Eigen::VectorXd impulse_length(m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Constraint& row = cluster.rows[k];
    impulse_length(k) =
        h * (cluster.inverse_mass[row.i] + (row.j >= 0 ? cluster.inverse_mass[row.j] : 0.0));
  }

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
      phi(k) = equality[k] ? gaps(k) : fischer_burmeister(impulse_length(k) * z(k), gaps(k));
    }
  };

  std::vector<Vec3> x, xt;
  positions(out.z, x);
  Eigen::VectorXd gaps, phi, gt, pt, trial, step;
  residual(out.z, x, gaps, phi);
  Tridiagonal bands;
  for (;;) {
    out.status.residual = residual_norm(phi);
    if (out.status.residual <= tolerance) {
      out.status.converged = true;
      break;
    }
    if (out.status.iterations >= newton_limit) break;
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
        const double a = impulse_length(k) * out.z(k), b = gaps(k), r = std::sqrt(a * a + b * b);
        // At (0, 0) any element of the generalized Jacobian will do; take the direction (1, 1).
        const double da = r > 0 ? 1 - a / r : 1 - M_SQRT1_2;
        const double db = r > 0 ? 1 - b / r : 1 - M_SQRT1_2;
        J.row(k) = db * dgap.row(k);
        J(k, k) += da * impulse_length(k);
      }
      step = solve_linear(J, -phi);
    }
    const double merit = phi.squaredNorm();
    double t = 1.0;
    bool decreased = false;
    for (int halvings = 0;; ++halvings) {
      trial = out.z + t * step;
      positions(trial, xt);
      residual(trial, xt, gt, pt);
      if (pt.squaredNorm() <= (1 - 1e-4 * t) * merit) {
        decreased = true;
        break;
      }
      if (halvings == line_search_limit) break;
      t *= 0.5;
    }
    if (!decreased) {
      out.line_search_failed = true;
      break;
    }
    std::swap(out.z, trial);
    std::swap(x, xt);
    std::swap(gaps, gt);
    std::swap(phi, pt);
  }
  out.x = std::move(x);
  out.impulse = structure.impulse(uq, out.z);
  return out;
}

}  // namespace deli
