#include "integrators/reflection.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/parallel.hpp"
#include "solvers/chain_projection.hpp"
#include "solvers/cluster_matrices.hpp"
#include "solvers/least_norm.hpp"
#include "solvers/nonnegative_qp.hpp"

namespace deli {

Eigen::MatrixXd projected_normals(const LocalCluster& cluster, const std::vector<bool>& equality,
                                  const std::vector<Vec3>& x, const Box& box) {
  std::vector<int> eq_rows, in_rows;
  for (std::size_t k = 0; k < cluster.rows.size(); ++k) {
    (equality[k] ? eq_rows : in_rows).push_back(static_cast<int>(k));
  }
  Eigen::MatrixXd N = gradient_matrix(cluster, in_rows, x, box);
  Eigen::MatrixXd Y;
  if (!eq_rows.empty() && !project_out_chains(cluster, eq_rows, x, box, N, Y)) {
    // N <- (I - F (F^T W F)^+ F^T W) G: normals in the rod manifold's cotangent space.
    const Eigen::VectorXd w = inverse_mass_diagonal(cluster);
    const Eigen::MatrixXd F = gradient_matrix(cluster, eq_rows, x, box);
    const Eigen::MatrixXd WF = w.asDiagonal() * F;
    const Eigen::MatrixXd FWF = F.transpose() * WF;
    least_norm_solve(FWF, WF.transpose() * N, Y);
    N -= F * Y;
  }
  return N;
}

Eigen::VectorXd ShadowOperator::hessian_times(const Eigen::VectorXd& v, bool with_outside) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(v.size());
  const double* in = v.data();
  double* to = out.data();
  for (std::size_t k = 0; k < pair_count; ++k) {
    const LocalPair& b = pairs[k];
    Eigen::Vector3d dv(in[3 * b.a], in[3 * b.a + 1], in[3 * b.a + 2]);
    if (b.b >= 0) {
      dv -= Eigen::Vector3d(in[3 * b.b], in[3 * b.b + 1], in[3 * b.b + 2]);
    } else if (with_outside) {
      const Vec3 velocity = momenta[b.outside] * (1.0 / mass[b.outside]);
      dv -= Eigen::Vector3d(velocity.x, velocity.y, velocity.z);
    }
    const Eigen::Vector3d f = b.block->block * dv;
    Eigen::Map<Eigen::Vector3d>(to + 3 * b.a) += f;
    if (b.b >= 0) Eigen::Map<Eigen::Vector3d>(to + 3 * b.b) -= f;
  }
  return out;
}

namespace {
// One solve's matrices, kept per number of rows in the solve (the set changes within a
// call); row counts above kRowCountsKeptApart (large clusters, rare) share one.
constexpr std::size_t kRowCountsKeptApart = 16;
struct SolveScratch {
  Eigen::MatrixXd NV, KN, Q;
  Eigen::VectorXd c, lambda;
};

// reflect()'s vectors and matrices, kept between calls: a hard-sphere fluid reflects a few
// small clusters every step, and their shapes repeat, so each keeps its storage (Eigen
// reallocates only when a size changes). The arithmetic is the same expressions into kept
// objects; nothing is carried from one call to the next.
struct ReflectionScratch {
  std::vector<int> eq_rows, in_rows, set, rows;
  std::vector<char> reflected, ever_in_set;
  Eigen::VectorXd w, k_diag, flat, weighted_flat, total_lambda, normal_velocity;
  Eigen::MatrixXd N, Y;
  std::vector<SolveScratch> solves = std::vector<SolveScratch>(kRowCountsKeptApart + 1);
  SolveScratch& solve_of(std::size_t rows) {
    return solves[rows <= kRowCountsKeptApart ? rows : 0];
  }
  // Momenta after each solve; the first `history_size` entries are this call's.
  std::vector<Eigen::VectorXd> history;
  std::size_t history_size = 0;
};

// The columns `columns` of N, in that order, as NV.
void select_columns(const Eigen::MatrixXd& N, const std::vector<int>& columns,
                    Eigen::MatrixXd& NV) {
  NV.resize(N.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k) {
    NV.col(static_cast<Eigen::Index>(k)) = N.col(columns[k]);
  }
}

// The kinetic energy's quadratic over the columns `columns` of N: their scratch with
// NV = N[:, columns], KN = K NV and Q = NV^T K NV (K = diag(k_diag)); c is the caller's.
SolveScratch& kinetic_form(ReflectionScratch& s, const Eigen::MatrixXd& N,
                           const std::vector<int>& columns, const Eigen::VectorXd& k_diag) {
  SolveScratch& solve = s.solve_of(columns.size());
  select_columns(N, columns, solve.NV);
  solve.KN.noalias() = k_diag.asDiagonal() * solve.NV;
  solve.Q.noalias() = solve.NV.transpose() * solve.KN;
  return solve;
}

// Algorithm 2 for two inequality rows (no equality row, E = H) in closed form, as most
// contact clusters of a hard-sphere fluid are (88-96 % of its clusters of several rows; through
// the general loop below they took 3 % of a one-thread run). With K = W / 2 each solve's QP is
// min 1/2 lambda^T (A / 2) lambda + v^T lambda over lambda >= 0 on the approaching rows, A =
// N^T W N and v their normal velocities: for A positive definite its one minimiser is the
// interior solution where both are positive, else the better single-row one. Anything else (a
// cap, a stall, a singular A, a solve past kTwoRowSolves, momenta met again) returns false with
// p untouched, and the general loop reflects the cluster from the start. True: settled, after
// `solves` solves.
bool reflect_two_rows(const Eigen::MatrixXd& N, const Eigen::VectorXd& w, double tolerance,
                      const SolverLimits& limits, Eigen::VectorXd& flat, double total[2],
                      bool reflected[2], int& solves) {
  constexpr int kTwoRowSolves = 8;
  // Two rows of one cluster share a particle: three particles at most.
  constexpr Eigen::Index kCoordinates = 9;
  const Eigen::Index m = N.rows();
  if (m > kCoordinates) return false;
  const double* n0 = N.col(0).data();
  const double* n1 = N.col(1).data();
  double a00 = 0.0, a01 = 0.0, a11 = 0.0;
  for (Eigen::Index k = 0; k < m; ++k) {
    a00 += n0[k] * w(k) * n0[k];
    a01 += n0[k] * w(k) * n1[k];
    a11 += n1[k] * w(k) * n1[k];
  }
  const double det = a00 * a11 - a01 * a01;
  if (!(a00 > 0.0 && a11 > 0.0 && det > 1e-12 * a00 * a11)) return false;
  // The momenta after each solve (no heap: this runs for most contact clusters).
  std::array<std::array<double, kCoordinates>, kTwoRowSolves> seen;
  for (int iteration = 0;; ++iteration) {
    double v[2] = {0.0, 0.0};
    for (Eigen::Index k = 0; k < m; ++k) {
      const double velocity = w(k) * flat(k);
      v[0] += n0[k] * velocity;
      v[1] += n1[k] * velocity;
    }
    const bool approaching[2] = {v[0] < -tolerance, v[1] < -tolerance};
    if (!approaching[0] && !approaching[1]) return true;
    if (iteration >= limits.reflection_solves || iteration >= kTwoRowSolves) return false;
    // The QP's gradient at zero is v; a row's own minimiser is -2 v / a.
    const double accepted = 1e-14 * std::max(1.0, std::max(approaching[0] ? std::abs(v[0]) : 0.0,
                                                           approaching[1] ? std::abs(v[1]) : 0.0));
    double lambda[2] = {0.0, 0.0};
    auto alone = [&](int k) {
      const double a = k == 0 ? a00 : a11;
      if (!(v[k] < -accepted)) return false;
      lambda[k] = -2.0 * v[k] / a;
      lambda[1 - k] = 0.0;
      // The other row's gradient there, where it is in the set: it must not be negative.
      return !approaching[1 - k] || 0.5 * a01 * lambda[k] + v[1 - k] >= -accepted;
    };
    if (approaching[0] && approaching[1]) {
      lambda[0] = -2.0 * (a11 * v[0] - a01 * v[1]) / det;
      lambda[1] = -2.0 * (a00 * v[1] - a01 * v[0]) / det;
      if (!(lambda[0] > 0.0 && lambda[1] > 0.0) && !alone(0) && !alone(1)) return false;
    } else if (!alone(approaching[0] ? 0 : 1)) {
      return false;
    }
    for (Eigen::Index k = 0; k < m; ++k) flat(k) += n0[k] * lambda[0] + n1[k] * lambda[1];
    for (int k = 0; k < 2; ++k) {
      total[k] += lambda[k];
      reflected[k] = reflected[k] || lambda[k] > 0.0;
    }
    ++solves;
    for (int h = 0; h < iteration; ++h) {
      const std::array<double, kCoordinates>& before = seen[static_cast<std::size_t>(h)];
      if (std::equal(flat.data(), flat.data() + m, before.begin())) return false;
    }
    std::copy(flat.data(), flat.data() + m, seen[static_cast<std::size_t>(iteration)].begin());
  }
}

}  // namespace

ReflectionStats reflect(const LocalCluster& cluster, const std::vector<bool>& equality,
                        const std::vector<Vec3>& q, std::vector<Vec3>& p, const Box& box,
                        ReflectionOperator op, double tolerance, const SolverLimits& limits,
                        const ShadowOperator* shadow) {
  thread_local ReflectionScratch s;
  std::vector<int>& eq_rows = s.eq_rows;
  std::vector<int>& in_rows = s.in_rows;
  eq_rows.clear();
  in_rows.clear();
  for (std::size_t k = 0; k < cluster.rows.size(); ++k) {
    (equality[k] ? eq_rows : in_rows).push_back(static_cast<int>(k));
  }
  ReflectionStats stats;
  if (in_rows.empty()) {
    stats.settled = true;
    return stats;
  }
  const Eigen::VectorXd& w = s.w;
  inverse_mass_diagonal(cluster, s.w);
  // N = G - F Y, Y = (F^T W F)^+ F^T W G: projected_normals' N, with Y (the equality rows'
  // share of an impulse N lambda is -Y lambda) from the same decomposition instead of a
  // second one.
  Eigen::MatrixXd& N = s.N;
  Eigen::MatrixXd& Y = s.Y;
  gradient_matrix(cluster, in_rows, q, box, N);
  // Chains of rods in O(rows); other equality rows through the dense pseudo-inverse.
  if (!eq_rows.empty() && !project_out_chains(cluster, eq_rows, q, box, N, Y)) {
    const Eigen::MatrixXd F = gradient_matrix(cluster, eq_rows, q, box);
    const Eigen::MatrixXd WF = w.asDiagonal() * F;
    const Eigen::MatrixXd FWF = F.transpose() * WF;
    least_norm_solve(FWF, WF.transpose() * N, Y);
    N -= F * Y;
  }
  stats.row_impulse.assign(cluster.rows.size(), 0.0);
  // A QP limit below the three iterations Lawson-Hanson takes for two rows is the general
  // loop's to hit (and count).
  const bool two_rows_closed = eq_rows.empty() && !shadow &&
                               op == ReflectionOperator::generalized && in_rows.size() == 2 &&
                               (limits.qp_iterations == 0 || limits.qp_iterations >= 3);
  if (two_rows_closed) {
    flatten(p, s.flat);
    double total[2] = {0.0, 0.0};
    bool reflected[2] = {false, false};
    int solves = 0;
    if (reflect_two_rows(N, w, tolerance, limits, s.flat, total, reflected, solves)) {
      stats.settled = true;
      stats.iterations = solves;
      for (int k = 0; k < 2; ++k) {
        stats.row_impulse[static_cast<std::size_t>(in_rows[static_cast<std::size_t>(k)])] =
            total[k];
        stats.reflected += reflected[k] ? 1 : 0;
      }
      unflatten(s.flat, p);
      return stats;
    }
  }
  Eigen::VectorXd& total_lambda = s.total_lambda;
  total_lambda.setZero(static_cast<Eigen::Index>(in_rows.size()));
  s.k_diag = 0.5 * w;  // K = M^-1 / 2 (E = H)
  const Eigen::VectorXd& k_diag = s.k_diag;
  Eigen::VectorXd& flat = s.flat;
  flatten(p, flat);
  std::vector<char>& reflected = s.reflected;
  reflected.assign(in_rows.size(), 0);

  // Momenta after each solve: a later solve landing on one of them bit for bit has entered a
  // cycle (e.g. a particle pinned between two parallel walls bounces from one to the other
  // for ever), which no number of further iterations leaves.
  s.history_size = 0;
  std::vector<char>& ever_in_set = s.ever_in_set;
  ever_in_set.assign(in_rows.size(), 0);
  bool stopped = false;
  for (int iteration = 0;; ++iteration) {
    // N^T (W p), W p made first (what the product would make as its own temporary).
    s.weighted_flat.noalias() = w.asDiagonal() * flat;
    s.normal_velocity.noalias() = N.transpose() * s.weighted_flat;
    const Eigen::VectorXd& normal_velocity = s.normal_velocity;
    std::vector<int>& set = s.set;
    set.clear();
    for (std::size_t k = 0; k < in_rows.size(); ++k) {
      const bool approaching = normal_velocity(static_cast<Eigen::Index>(k)) < -tolerance;
      if (op == ReflectionOperator::moreau ? true : approaching) set.push_back(static_cast<int>(k));
    }
    if (op == ReflectionOperator::generalized && set.empty()) {
      stats.settled = true;
      break;
    }
    if (op == ReflectionOperator::moreau && iteration == 1) break;
    for (int k : set) ever_in_set[k] = 1;
    if (iteration >= limits.reflection_solves) {
      stats.capped = true;
      stopped = true;
      break;
    }
    // E = H: K = M^-1 / 2, Q = N^T K N, c = 2 N^T K p.
    SolveScratch& solve = kinetic_form(s, N, set, k_diag);
    Eigen::MatrixXd &NV = solve.NV, &KN = solve.KN, &Q = solve.Q;
    Eigen::VectorXd &c = solve.c, &lambda = solve.lambda;
    c.noalias() = 2.0 * (KN.transpose() * flat);
    bool solved = false;
    if (shadow) {
      // K~ = K + h^2/12 W d2V W (W = M^-1): the Hessian acts on velocities.
      const double s12 = shadow->h * shadow->h / 12.0;
      const Eigen::MatrixXd WN = w.asDiagonal() * NV;
      const Eigen::VectorXd velocity = w.asDiagonal() * flat;
      Eigen::MatrixXd HWN(WN.rows(), WN.cols());
      Eigen::VectorXd Hv;
      // The Hessian on each column of W N and on the velocities: products of their own, each
      // the serial loop whichever thread makes it, on as many threads as there are products
      // where each passes enough blocks (the default input's clusters: 1300 blocks, two
      // products, 5.6 us each, 9 % of its loop on two threads when made in turn).
      const std::size_t products = static_cast<std::size_t>(WN.cols()) + 1;
      auto product = [&](std::size_t k) {
        if (k + 1 < products) {
          HWN.col(static_cast<Eigen::Index>(k)) =
              shadow->hessian_times(WN.col(static_cast<Eigen::Index>(k)), false);
        } else {
          Hv = shadow->hessian_times(velocity, true);
        }
      };
      constexpr std::size_t kBlocksToSplit = 256;
      const int chunks = shadow->pair_count < kBlocksToSplit ? 1 : static_cast<int>(products);
      for_each_chunk(products, chunks, [&](int, std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) product(k);
      });
      const Eigen::MatrixXd Qs = Q + s12 * (WN.transpose() * HWN);
      const Eigen::VectorXd cs = c + 2.0 * s12 * (WN.transpose() * Hv);
      const Eigen::LDLT<Eigen::MatrixXd> check(Qs);
      const bool positive =
          check.info() == Eigen::Success && check.isPositive() &&
          check.vectorD().minCoeff() > 1e-14 * Qs.diagonal().cwiseAbs().maxCoeff();
      if (positive) {
        const SolverStatus qp = solve_nonnegative_qp(
            Qs, cs, lambda, 1e-14 * std::max(1.0, cs.lpNorm<Eigen::Infinity>()),
            limits.qp_iterations);
        if (!qp.converged) ++stats.qp_caps;
        solved = qp.converged && lambda.lpNorm<Eigen::Infinity>() > 0.0;
      }
      if (!solved) ++stats.shadow_fallbacks;
    }
    bool optimal = true;
    if (!solved) {
      const SolverStatus qp = solve_nonnegative_qp(
          Q, c, lambda, 1e-14 * std::max(1.0, c.lpNorm<Eigen::Infinity>()), limits.qp_iterations);
      if (!qp.converged) ++stats.qp_caps;
      optimal = qp.converged;
    }
    ++stats.iterations;
    if (!optimal || lambda.lpNorm<Eigen::Infinity>() == 0.0) {
      stats.capped = true;  // approaching, yet no energy-preserving impulse (found): stalled
      stopped = true;
      break;
    }
    flat += NV * lambda;
    for (std::size_t k = 0; k < set.size(); ++k)
      total_lambda(set[k]) += lambda(static_cast<Eigen::Index>(k));
    for (std::size_t k = 0; k < set.size(); ++k) {
      if (lambda(static_cast<Eigen::Index>(k)) > 0) reflected[set[k]] = 1;
    }
    if (op == ReflectionOperator::generalized) {
      for (std::size_t h = 0; h < s.history_size; ++h) {
        if (s.history[h] == flat) stats.cycled = true;
      }
      if (stats.cycled) {
        stopped = true;
        break;
      }
      if (s.history.size() == s.history_size) s.history.emplace_back();
      s.history[s.history_size++] = flat;
    }
  }
  if (stopped) {
    // No energy-preserving way out: take the least kinetic energy change that leaves every
    // row met so far non-approaching (an inelastic Moreau step, min |p' - p|_K over
    // p' = p + N lambda, lambda >= 0), so the step ends feasible. Counted by the caller.
    std::vector<int>& rows = s.rows;
    rows.clear();
    for (std::size_t k = 0; k < in_rows.size(); ++k) {
      if (ever_in_set[k]) rows.push_back(static_cast<int>(k));
    }
    SolveScratch& solve = kinetic_form(s, N, rows, k_diag);
    Eigen::MatrixXd &NV = solve.NV, &KN = solve.KN, &Q = solve.Q;
    Eigen::VectorXd &c = solve.c, &lambda = solve.lambda;
    c.noalias() = KN.transpose() * flat;
    const SolverStatus qp = solve_nonnegative_qp(
        Q, c, lambda, 1e-14 * std::max(1.0, c.lpNorm<Eigen::Infinity>()), limits.qp_iterations);
    if (!qp.converged) ++stats.qp_caps;
    flat += NV * lambda;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      total_lambda(rows[k]) += lambda(static_cast<Eigen::Index>(k));
      if (lambda(static_cast<Eigen::Index>(k)) > 0) reflected[rows[k]] = 1;
    }
  }
  for (char r : reflected) stats.reflected += r ? 1 : 0;
  for (std::size_t k = 0; k < in_rows.size(); ++k)
    stats.row_impulse[in_rows[k]] = total_lambda(static_cast<Eigen::Index>(k));
  if (!eq_rows.empty()) {
    const Eigen::VectorXd along_equalities = -(Y * total_lambda);
    for (std::size_t k = 0; k < eq_rows.size(); ++k) {
      stats.row_impulse[eq_rows[k]] = along_equalities(static_cast<Eigen::Index>(k));
    }
  }
  unflatten(flat, p);
  return stats;
}

}  // namespace deli
