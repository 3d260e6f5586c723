#include "integrators/constrained_integrator.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>

#include "constraints/clusters.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "integrators/lone_row_reflection.hpp"
#include "solvers/cluster_matrices.hpp"
#include "solvers/momentum_update.hpp"
#include "solvers/position_problem.hpp"
#include "solvers/position_update.hpp"

namespace deli {

ConstrainedIntegrator::ConstrainedIntegrator(const ForceField& force_field,
                                             ConstraintSet constraints, double timestep,
                                             double skin, ReflectionOperator reflection,
                                             ReflectionEnergy energy, const Particles& particles)
    : constraints_(std::move(constraints)),
      engine_(force_field, skin, constraints_.contact_reach(particles)),
      dt_(timestep),
      reflection_(reflection),
      energy_(energy) {
  equality_clusters_.prepare(constraints_.equalities, particles.mass);
}

std::size_t ConstrainedIntegrator::cluster_rows(const std::vector<Constraint>& rows,
                                                const Particles& particles) {
  if (!equality_clusters_.prepared_for(particles.size())) {
    equality_clusters_.prepare(constraints_.equalities, particles.mass);
  }
  if (&rows == &constraints_.equalities) return equality_clusters_.all().size();
  found_clusters_ = find_clusters(rows, particles.size());
  return found_clusters_.size();
}

bool ConstrainedIntegrator::equalities_hold_every_particle(const Particles& particles) {
  if (!equality_clusters_.prepared_for(particles.size())) {
    equality_clusters_.prepare(constraints_.equalities, particles.mass);
  }
  return equality_clusters_.hold_every_particle();
}

const PreparedCluster* ConstrainedIntegrator::prepared_cluster(const std::vector<Constraint>& rows,
                                                               std::size_t index) const {
  if (&rows == &constraints_.equalities) return &equality_clusters_.all()[index];
  return equality_clusters_.find(found_clusters_[index], rows);
}

std::vector<Vec3> gather(const std::vector<Vec3>& all, const std::vector<std::int32_t>& which) {
  std::vector<Vec3> out;
  gather(all, which, out);
  return out;
}

void gather(const std::vector<Vec3>& all, const std::vector<std::int32_t>& which,
            std::vector<Vec3>& out) {
  out.clear();
  out.reserve(which.size());
  for (std::int32_t i : which) out.push_back(all[i]);
}

void scatter(const std::vector<Vec3>& local, const std::vector<std::int32_t>& which,
             std::vector<Vec3>& all) {
  for (std::size_t k = 0; k < which.size(); ++k) all[which[k]] = local[k];
}

namespace {
// a[i] == b[i] for every listed particle, bit for bit (a signed zero counts as itself).
bool same_vectors(const std::vector<std::int32_t>& particles, const std::vector<Vec3>& a,
                  const std::vector<Vec3>& b) {
  for (std::int32_t i : particles) {
    if (std::memcmp(&a[i], &b[i], sizeof(Vec3)) != 0) return false;
  }
  return true;
}

// A residual for a message: std::to_string prints 1e-9 as 0.000000.
std::string scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3e", value);
  return text;
}
}  // namespace

void ConstrainedIntegrator::midpoint_failure(const System& system, double change) const {
  throw SimulationError("step " + std::to_string(system.step + 1) +
                        ": the implicit-midpoint fixed point (all atoms) did not converge: last "
                        "change " +
                        scientific(change) + " sigma after " +
                        std::to_string(constraints_.limits.midpoint_passes) +
                        " passes ([constraints.limits] midpoint_passes); reduce the timestep");
}

namespace {

std::string describe(const Constraint& c, const Particles& particles) {
  std::string s = std::string(kind_name(c.kind)) + " on atom " + std::to_string(particles.id[c.i]);
  if (c.j >= 0) s += " and atom " + std::to_string(particles.id[c.j]);
  return s;
}

}  // namespace

namespace {
// r . J for an impulse z along a pair row's gradient at positions x: z |d|. One-particle
// rows (walls, strings) act from outside the system and add nothing, as LAMMPS' walls.
double pair_virial(const Constraint& c, double z, const Vec3* x, const Box& box) {
  if (c.j < 0) return 0.0;
  return z * norm(box.minimum_image(x[c.i] - x[c.j]));
}
}  // namespace

const Cluster& ConstrainedIntegrator::cluster_at(const std::vector<Constraint>& rows,
                                                 std::size_t index) const {
  if (&rows == &constraints_.equalities) return equality_clusters_.all()[index].cluster;
  return found_clusters_[index];
}

template <class Solve>
void ConstrainedIntegrator::around_clusters(const std::vector<Constraint>& rows,
                                            const ClusterPasses* passes, int chunk,
                                            std::size_t begin, std::size_t end,
                                            const Solve& solve) const {
  if (!passes) {
    solve();
    return;
  }
  // The clusters' particles as runs: a cluster whose particles are consecutive (they are
  // ascending) joins a run of consecutive particles the last one left; any other is a list.
  auto runs = [&](const std::function<void(int, const ParticleRun&)>& pass) {
    ParticleRun run{nullptr, 0, 0};
    for (std::size_t k = begin; k < end; ++k) {
      const std::vector<std::int32_t>& particles = cluster_at(rows, k).particles;
      const auto first = static_cast<std::size_t>(particles.front());
      const bool consecutive =
          static_cast<std::size_t>(particles.back()) - first + 1 == particles.size();
      if (consecutive && run.count > 0 && run.first + run.count == first) {
        run.count += particles.size();
        continue;
      }
      if (run.count > 0) pass(chunk, run);
      run = consecutive ? ParticleRun{nullptr, first, particles.size()}
                        : ParticleRun{particles.data(), 0, particles.size()};
      if (!consecutive) {
        pass(chunk, run);
        run.count = 0;
      }
    }
    if (run.count > 0) pass(chunk, run);
  };
  runs(passes->before);
  solve();
  runs(passes->after);
}

namespace {
// A cluster's position update that did not converge, thrown out of the cluster loop: the
// report (the problem written to a file, then the message) is made once, for the cluster a
// serial loop meets first, after the loop.
struct UnconvergedCluster {
  PositionProblem problem;
  std::string before_file, after_file;  // the message around "the problem FILE"
};

// A run of chains in the lockstep kernels costs a whole group of RodChainLanes::width lanes
// whatever its count (lanes without a chain repeat the first one): about four chains solved
// alone with AVX2, more in a portable build. Rigid melt (100 chains of 40 beads), two threads,
// each chunk's 50 chains as 6 full runs and a run of 2: with the 2 solved alone, position update
// 0.896x and momentum update 0.906x (AVX2), 0.877x and 0.912x (portable); one thread, its run
// of 4 alone: 1.000x and 0.988x (AVX2), 0.963x and 0.973x (portable). Shorter runs than this
// are solved alone.
constexpr std::size_t kFewestChainsTogether = 5;

// Clusters begin..end-1 in index order: runs of up to RodChainLanes::width consecutive chains
// of one length (chain_of(index) non-null) go to together(chains, indices, count) with
// count >= kFewestChainsTogether; every other cluster, and each chain of a shorter run, to
// alone(index).
template <class ChainOf, class Alone, class Together>
void by_chain_runs(std::size_t begin, std::size_t end, const ChainOf& chain_of, const Alone& alone,
                   const Together& together) {
  constexpr std::size_t width = RodChainLanes::width;
  std::size_t index = begin;
  while (index < end) {
    const RodChain* chains[width];
    std::size_t indices[width];
    std::size_t count = 0;
    for (; index < end && count < width; ++index) {
      const RodChain* chain = chain_of(index);
      if (!chain || (count > 0 && chain->rows() != chains[0]->rows())) break;
      chains[count] = chain;
      indices[count++] = index;
    }
    if (count == 0) {
      alone(index++);
      continue;
    }
    if (count < kFewestChainsTogether) {
      for (std::size_t l = 0; l < count; ++l) alone(indices[l]);
      continue;
    }
    together(chains, indices, count);
  }
}
}  // namespace

// The clusters are independent (disjoint particles): they are solved in chunks of clusters
// on several threads, each cluster by the same operations as alone. What the serial loop
// accumulated as it went (the virial, the solve statistics) is joined after the loop in
// cluster order, so the results are the same bits on any number of threads.
double ConstrainedIntegrator::solve_positions(
    System& system, const std::vector<Constraint>& rows, const std::vector<bool>& equality,
    const std::vector<Vec3>& q, const std::vector<Vec3>& delta, std::vector<Vec3>& impulse,
    const std::vector<char>* delta_changed, const SolvedEqualities* solved_equalities,
    const ClusterPasses* passes) {
  const Particles& particles = system.particles;
  const std::size_t cluster_count = cluster_rows(rows, particles);
  const bool equality_rows = &rows == &constraints_.equalities;
  // The equality rows passed as themselves are all held as equalities (every caller's
  // `equality` is all true for them): their chains skip the test row by row.
  assert(!equality_rows || std::find(equality.begin(), equality.end(), false) == equality.end());
  if (equality_rows) {
    equality_iterations_.resize(cluster_count, 0);
    equality_chain_virial_.resize(cluster_count, 0.0);
    equality_chain_solved_.resize(cluster_count, 0);
  }
  // A chain's virial is one term, a generic cluster's one per row.
  virial_terms_.reset(cluster_count,
                      [&](std::size_t k) { return cluster_at(rows, k).rows.size(); });
  cluster_iterations_.assign(cluster_count, -1);
  auto solve_cluster = [&](std::size_t index, RodChainWorkspace& chain_work) {
    const PreparedCluster* prepared = prepared_cluster(rows, index);
    const Cluster& cluster = prepared ? prepared->cluster : found_clusters_[index];
    if (delta_changed && equality_rows) {
      bool changed = false;
      for (std::int32_t i : cluster.particles) changed = changed || (*delta_changed)[i];
      if (!changed) {
        cluster_iterations_[index] = equality_iterations_[index];
        return;
      }
    }
    if (prepared && prepared->chain) {
      // A chain of rods held as equalities: the chain kernel (same numbers, no gathering).
      bool held = true;
      if (!equality_rows) {
        for (std::int32_t r : cluster.rows) held = held && equality[r];
      }
      const auto own = static_cast<std::size_t>(prepared - equality_clusters_.all().data());
      if (held && solved_equalities && own < equality_chain_solved_.size() &&
          equality_chain_solved_[own] &&
          same_vectors(cluster.particles, delta, solved_equalities->delta)) {
        for (std::int32_t i : cluster.particles) impulse[i] = solved_equalities->impulse[i];
        virial_terms_.add(index, equality_chain_virial_[own]);
        cluster_iterations_[index] = equality_iterations_[own];
        return;
      }
      SolverStatus status;
      double chain_virial = 0.0;
      if (held && prepared->chain->solve_positions(
                      q.data(), delta.data(), dt_, system.box, constraints_.tolerances.solver,
                      constraints_.limits.newton, constraints_.limits.line_search, chain_work,
                      impulse.data(), chain_virial, status)) {
        virial_terms_.add(index, chain_virial);
        cluster_iterations_[index] = status.iterations;
        if (equality_rows) {
          equality_iterations_[index] = status.iterations;
          equality_chain_virial_[index] = chain_virial;
          equality_chain_solved_[index] = 1;
        }
        return;
      }
    }
    if (equality_rows) equality_chain_solved_[index] = 0;
    std::optional<LocalCluster> built;
    std::optional<ClusterRows> built_structure;
    if (!prepared) built_structure.emplace(built.emplace(localize(cluster, rows, particles.mass)));
    const LocalCluster& local = prepared ? prepared->local : *built;
    const ClusterRows& structure = prepared ? *prepared->structure : *built_structure;
    std::vector<bool> local_equality;
    for (std::int32_t r : cluster.rows) local_equality.push_back(equality[r]);
    const std::vector<Vec3> q_local = gather(q, cluster.particles);
    std::vector<Vec3> x0_local = gather(delta, cluster.particles);
    for (std::size_t k = 0; k < x0_local.size(); ++k) x0_local[k] += q_local[k];
    const PositionUpdate solved =
        solve_position_update(structure, local_equality, q_local, x0_local, dt_, system.box,
                              constraints_.tolerances.solver, constraints_.limits.newton,
                              constraints_.limits.line_search);
    cluster_iterations_[index] = solved.status.iterations;
    if (equality_rows) equality_iterations_[index] = solved.status.iterations;
    if (!solved.status.converged) {
      UnconvergedCluster failure;
      PositionProblem& problem = failure.problem;
      problem.step = system.step + 1;
      problem.h = dt_;
      problem.tolerance = constraints_.tolerances.solver;
      problem.newton_limit = constraints_.limits.newton;
      problem.line_search_limit = constraints_.limits.line_search;
      problem.box = system.box;
      for (std::int32_t i : cluster.particles) problem.ids.push_back(particles.id[i]);
      problem.cluster = local;
      problem.equality = local_equality;
      problem.q = q_local;
      problem.x0 = x0_local;
      problem.failed_residual = solved.status.residual;
      problem.failed_iterations = solved.status.iterations;
      failure.before_file =
          "step " + std::to_string(system.step + 1) +
          ": the position update did not converge for the cluster of " +
          std::to_string(cluster.particles.size()) + " atoms from atom " +
          std::to_string(particles.id[cluster.particles.front()]) + " (" +
          std::to_string(cluster.rows.size()) +
          " constraints, first: " + describe(rows[cluster.rows.front()], particles) +
          "): residual " + scientific(solved.status.residual) + " sigma after " +
          std::to_string(solved.status.iterations) + " Newton iterations" +
          (solved.line_search_failed ? " (its line search found no step that lowers the residual)"
                                     : " ([constraints.limits] newton = " +
                                           std::to_string(constraints_.limits.newton) + ")");
      failure.after_file =
          "; deli solve-problem FILE solves it again" +
          std::string(setting_up_
                          ? "; the equality constraints cannot all hold from the starting "
                            "configuration (infeasible lengths, or a start far from them): "
                            "check the rod and string lengths against the starting distances"
                          : "; reduce the timestep");
      throw failure;
    }
    for (std::size_t k = 0; k < cluster.particles.size(); ++k) {
      impulse[cluster.particles[k]] = solved.impulse[k];
    }
    for (std::size_t r = 0; r < local.rows.size(); ++r) {
      virial_terms_.add(index, pair_virial(local.rows[r], solved.z(static_cast<Eigen::Index>(r)),
                                           q_local.data(), system.box));
    }
  };
  // The chain solve_cluster would give to the chain kernel (not reused from an earlier
  // call), or null.
  auto chain_to_solve = [&](std::size_t index) -> const RodChain* {
    const PreparedCluster* prepared = prepared_cluster(rows, index);
    if (!prepared || !prepared->chain) return nullptr;
    const Cluster& cluster = prepared->cluster;
    if (delta_changed && equality_rows) {
      bool changed = false;
      for (std::int32_t i : cluster.particles) changed = changed || (*delta_changed)[i];
      if (!changed) return nullptr;
    }
    // Row numbers as unsigned: the bit's word and position without a signed division.
    if (!equality_rows) {
      for (const std::int32_t r : cluster.rows) {
        if (!equality[static_cast<std::uint32_t>(r)]) return nullptr;
      }
    }
    const auto own = static_cast<std::size_t>(prepared - equality_clusters_.all().data());
    if (solved_equalities && own < equality_chain_solved_.size() && equality_chain_solved_[own] &&
        same_vectors(cluster.particles, delta, solved_equalities->delta)) {
      return nullptr;
    }
    return prepared->chain.get();
  };
  const int chunks = chunks_for_work(cluster_count, rows.size());
  if (chain_works_.size() < static_cast<std::size_t>(chunks)) chain_works_.resize(chunks);
  if (chain_lanes_.size() < static_cast<std::size_t>(chunks)) chain_lanes_.resize(chunks);
  try {
    for_each_chunk(cluster_count, chunks, [&](int c, std::size_t begin, std::size_t end) {
      RodChainWorkspace& work = chain_works_[static_cast<std::size_t>(c)];
      RodChainLanes& lanes = chain_lanes_[static_cast<std::size_t>(c)];
      // Consecutive chains of one length solved together; what they leave unsolved (and
      // every other cluster) is solved alone, in index order.
      auto alone = [&](std::size_t index) { solve_cluster(index, work); };
      auto together = [&](const RodChain** chains, const std::size_t* indices, std::size_t count) {
        constexpr std::size_t width = RodChainLanes::width;
        double chain_virial[width];
        SolverStatus status[width];
        bool solved[width];
        RodChain::solve_positions_lanes(chains, count, q.data(), delta.data(), dt_, system.box,
                                        constraints_.tolerances.solver, constraints_.limits.newton,
                                        lanes, impulse.data(), chain_virial, status, solved);
        for (std::size_t l = 0; l < count; ++l) {
          const std::size_t at = indices[l];
          if (!solved[l]) {
            solve_cluster(at, work);
            continue;
          }
          virial_terms_.add(at, chain_virial[l]);
          cluster_iterations_[at] = status[l].iterations;
          if (equality_rows) {
            equality_iterations_[at] = status[l].iterations;
            equality_chain_virial_[at] = chain_virial[l];
            equality_chain_solved_[at] = 1;
          }
        }
      };
      around_clusters(rows, passes, c, begin, end,
                      [&] { by_chain_runs(begin, end, chain_to_solve, alone, together); });
    });
  } catch (const UnconvergedCluster& failure) {
    const PositionProblem& problem = failure.problem;
    const std::string file = save_position_problem(
        "deli-failed-solve-step" + std::to_string(problem.step) + ".txt", problem);
    throw SimulationError(failure.before_file + "; the problem " + file + failure.after_file);
  }
  for (const int iterations : cluster_iterations_) {
    ++stats_.solves;
    stats_.solver_iterations += iterations;
    stats_.max_solver_iterations = std::max(stats_.max_solver_iterations, iterations);
  }
  double virial = 0.0;
  virial_terms_.add_to(virial);
  return virial;
}

double ConstrainedIntegrator::project_momenta(System& system, const std::vector<Constraint>& rows,
                                              const std::vector<Vec3>& x, std::vector<Vec3>& p,
                                              const ClusterPasses* passes) {
  const std::size_t cluster_count = cluster_rows(rows, system.particles);
  virial_terms_.reset(cluster_count,
                      [&](std::size_t k) { return cluster_at(rows, k).rows.size(); });
  const int chunks = chunks_for_work(cluster_count, rows.size());
  // Per chunk: the largest deviation of the rod lengths the chain kernels measured at x, or
  // -1 once a cluster went another way.
  std::vector<double> chunk_deviation(static_cast<std::size_t>(chunks), 0.0);
  auto project_cluster = [&](std::size_t index, RodChainWorkspace& chain_work, double& deviation) {
    const PreparedCluster* prepared = prepared_cluster(rows, index);
    const Cluster& cluster = prepared ? prepared->cluster : found_clusters_[index];
    double chain_virial = 0.0;
    if (prepared && prepared->chain &&
        prepared->chain->project_momenta(x.data(), p.data(), system.box, chain_work,
                                         chain_virial)) {
      virial_terms_.add(index, chain_virial);
      if (deviation >= 0.0) deviation = std::max(deviation, prepared->chain->measured_deviation());
      return;
    }
    deviation = -1.0;
    std::optional<LocalCluster> built;
    std::optional<ClusterRows> built_structure;
    if (!prepared) {
      built_structure.emplace(built.emplace(localize(cluster, rows, system.particles.mass)));
    }
    const LocalCluster& local = prepared ? prepared->local : *built;
    const ClusterRows& structure = prepared ? *prepared->structure : *built_structure;
    std::vector<Vec3> p_local = gather(p, cluster.particles);
    const std::vector<Vec3> x_local = gather(x, cluster.particles);
    Eigen::VectorXd mu;
    const SolverStatus status = project_momentum(structure, x_local, p_local, system.box,
                                                 constraints_.tolerances.velocity, mu);
    for (std::size_t r = 0; r < local.rows.size(); ++r) {
      virial_terms_.add(index, pair_virial(local.rows[r], mu(static_cast<Eigen::Index>(r)),
                                           x_local.data(), system.box));
    }
    if (!status.converged) {
      throw SimulationError(
          "step " + std::to_string(system.step) +
          ": the momentum update failed for the cluster of " +
          std::to_string(cluster.particles.size()) + " atoms from atom " +
          std::to_string(system.particles.id[cluster.particles.front()]) + " (" +
          std::to_string(cluster.rows.size()) +
          " constraints, first: " + describe(rows[cluster.rows.front()], system.particles) +
          "): normal velocities up to " + scientific(status.residual) +
          " sigma/tau remain after the projection (tolerance velocity = " +
          scientific(constraints_.tolerances.velocity) +
          "); the constraint matrix is singular beyond repair or the velocities are not finite");
    }
    scatter(p_local, cluster.particles, p);
  };
  auto chain_of = [&](std::size_t index) -> const RodChain* {
    const PreparedCluster* prepared = prepared_cluster(rows, index);
    return prepared ? prepared->chain.get() : nullptr;
  };
  if (chain_works_.size() < static_cast<std::size_t>(chunks)) chain_works_.resize(chunks);
  if (chain_lanes_.size() < static_cast<std::size_t>(chunks)) chain_lanes_.resize(chunks);
  // A failure is thrown once every chunk has ended: the lowest chunk's, whose loop stopped at
  // the first failing cluster a serial loop meets.
  for_each_chunk(cluster_count, chunks, [&](int c, std::size_t begin, std::size_t end) {
    RodChainWorkspace& work = chain_works_[static_cast<std::size_t>(c)];
    RodChainLanes& lanes = chain_lanes_[static_cast<std::size_t>(c)];
    double& deviation = chunk_deviation[static_cast<std::size_t>(c)];
    auto alone = [&](std::size_t index) { project_cluster(index, work, deviation); };
    auto together = [&](const RodChain** chains, const std::size_t* indices, std::size_t count) {
      bool solved[RodChainLanes::width];
      double chain_virial[RodChainLanes::width];
      RodChain::project_momenta_lanes(chains, count, x.data(), p.data(), system.box, lanes,
                                      chain_virial, solved);
      for (std::size_t l = 0; l < count; ++l) {
        if (!solved[l]) {
          project_cluster(indices[l], work, deviation);
          continue;
        }
        virial_terms_.add(indices[l], chain_virial[l]);
        if (deviation >= 0.0) deviation = std::max(deviation, chains[l]->measured_deviation());
      }
    };
    around_clusters(rows, passes, c, begin, end,
                    [&] { by_chain_runs(begin, end, chain_of, alone, together); });
  });
  projected_deviation_ = -1.0;
  if (&rows == &constraints_.equalities) {
    double largest = 0.0;
    bool measured = true;
    for (const double d : chunk_deviation) {
      measured = measured && d >= 0.0;
      largest = std::max(largest, d);
    }
    if (measured) projected_deviation_ = largest;
  }
  double virial = 0.0;
  virial_terms_.add_to(virial);
  return virial;
}

void ConstrainedIntegrator::setup(System& system) {
  Particles& P = system.particles;
  engine_.ensure_neighbors(system);
  // Start on the manifold: positions onto the equality constraints (a position update from
  // rest), then momenta tangent to it.
  if (!constraints_.equalities.empty()) {
    std::vector<Vec3> impulse(P.size());
    setting_up_ = true;
    solve_positions(system, constraints_.equalities,
                    std::vector<bool>(constraints_.equalities.size(), true), P.position,
                    std::vector<Vec3>(P.size()), impulse);
    setting_up_ = false;
    for (std::size_t i = 0; i < P.size(); ++i) P.position[i] += impulse[i] * (dt_ / P.mass[i]);
  }
  const double gap =
      constraints_.minimum_gap(P, P.position.data(), engine_.neighbors(), system.box);
  if (gap < -constraints_.tolerances.gap) {
    throw SimulationError(
        "the starting configuration overlaps: the smallest hard-sphere or wall "
        "gap is " +
        std::to_string(gap) + " sigma; start from a configuration without overlaps");
  }
  engine_.compute(system);
  project_velocities(system);
}

// A thermostat's kick projected onto the rods (twice a step): the momenta made, and the
// velocities made again, by the threads that project each chunk's clusters where the rods hold
// every particle, else in chunks. Made by the calling thread, with a vector allocated at each
// call, they were serial work on its path (the default input's thermostatted steps).
void ConstrainedIntegrator::project_velocities(System& system) {
  Particles& P = system.particles;
  const std::size_t n = P.size();
  std::vector<Vec3>& p = projected_momenta_;
  p.resize(n);
  const Vec3* velocity = P.velocity.data();
  const double* mass = P.mass.data();
  Vec3* momenta = p.data();
  auto make_momenta = [=](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) momenta[i] = velocity[i] * mass[i];
  };
  auto make_velocities = [&, mass, momenta](std::size_t begin, std::size_t end) {
    Vec3* v = P.velocity.data();
    for (std::size_t i = begin; i < end; ++i) v[i] = momenta[i] * (1.0 / mass[i]);
  };
  if (thread_count() > 1 && !constraints_.equalities.empty() && equalities_hold_every_particle(P)) {
    ClusterPasses passes;
    passes.before = [&](int, const ParticleRun& run) { run.for_each_range(make_momenta); };
    passes.after = [&](int, const ParticleRun& run) { run.for_each_range(make_velocities); };
    project_momenta(system, constraints_.equalities, P.position, p, &passes);
    return;
  }
  const int chunks = chunks_for_cheap(n);
  for_each_chunk(n, chunks,
                 [&](int, std::size_t begin, std::size_t end) { make_momenta(begin, end); });
  project_momenta(system, constraints_.equalities, P.position, p);
  for_each_chunk(n, chunks,
                 [&](int, std::size_t begin, std::size_t end) { make_velocities(begin, end); });
}

bool contains(const std::vector<Constraint>& rows, const Constraint& c) {
  for (const Constraint& r : rows) {
    if (same_row(r, c)) return true;
  }
  return false;
}

namespace {
std::uint64_t particle_key(const Constraint& c) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.i)) << 32) |
         static_cast<std::uint32_t>(c.j);
}
}  // namespace

void mark_contained(const std::vector<Constraint>& rows, const RowStretches& candidates,
                    std::vector<std::pair<std::uint64_t, std::int32_t>>& scratch,
                    std::vector<char>& contained) {
  contained.assign(candidates.size(), 0);
  if (rows.empty()) return;
  scratch.clear();
  for (std::size_t r = 0; r < rows.size(); ++r) {
    scratch.emplace_back(particle_key(rows[r]), static_cast<std::int32_t>(r));
  }
  std::sort(scratch.begin(), scratch.end());
  auto mark = [&](std::size_t k, const Constraint& candidate, double) {
    const std::uint64_t key = particle_key(candidate);
    auto at = std::lower_bound(scratch.begin(), scratch.end(),
                               std::pair<std::uint64_t, std::int32_t>{key, -1});
    // same_row decides among the rows on the same particles (a particle's walls).
    for (; at != scratch.end() && at->first == key; ++at) {
      if (same_row(rows[static_cast<std::size_t>(at->second)], candidate)) {
        contained[k] = 1;
        break;
      }
    }
  };
  candidates.for_each(0, candidates.size(), mark);
}

double normal_velocity(const Constraint& c, const Vec3& u, const std::vector<Vec3>& p,
                       const Particles& P) {
  double v = dot(u, p[c.i]) / P.mass[c.i];
  if (c.j >= 0) v -= dot(u, p[c.j]) / P.mass[c.j];
  return v;
}

// The Hessian blocks of the potential touching the clusters to reflect, at the current
// positions (the reflection's q): one scan of the neighbour list for all of them; then each
// cluster's shadow pairs, in one job over the blocks (the default input: 2400 blocks and two
// clusters a call, made on the calling thread alone they took 8 % of its loop on two threads,
// bench/README.md, "Stop 56").
void ConstrainedIntegrator::gather_hessian_blocks(const System& system,
                                                  const std::vector<Cluster>& clusters,
                                                  const std::vector<bool>& reflected) {
  const std::size_t n = system.particles.size();
  cluster_of_particle_.assign(n, -1);
  local_index_of_particle_.resize(n);
  hessian_mask_.assign(n, 0);
  reflected_number_.assign(clusters.size(), -1);
  std::int32_t count = 0;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (!reflected[c]) continue;
    reflected_number_[c] = count;
    const std::vector<std::int32_t>& members = clusters[c].particles;
    for (std::size_t k = 0; k < members.size(); ++k) {
      cluster_of_particle_[members[k]] = count;
      local_index_of_particle_[members[k]] = static_cast<std::int32_t>(k);
      hessian_mask_[members[k]] = 1;
    }
    ++count;
  }
  hessian_blocks_.clear();
  if (!engine_.force_field().pair_hessian_pieces(system, engine_.neighbors(), hessian_mask_,
                                                 hessian_blocks_)) {
    throw SimulationError(
        "shadow-Hamiltonian reflections need a pairwise Hessian, which "
        "harmonic angles lack: use energy = \"hamiltonian\"");
  }
  shadow_pairs_.make(hessian_blocks_, cluster_of_particle_.data(), local_index_of_particle_.data(),
                     static_cast<std::size_t>(count));
}

// Cluster c's Hessian blocks in the cluster's numbering (gather_hessian_blocks' pairs), with
// the momenta of the particles outside it that its blocks reach.
ShadowOperator ConstrainedIntegrator::shadow_operator(const System& system, std::size_t c,
                                                      const std::vector<Vec3>& p) const {
  const auto r = static_cast<std::size_t>(reflected_number_[c]);
  ShadowOperator shadow;
  shadow.h = dt_;
  shadow.pairs = shadow_pairs_.pairs(r);
  shadow.pair_count = shadow_pairs_.count(r);
  shadow.momenta = p.data();
  shadow.mass = system.particles.mass.data();
  return shadow;
}

// Reflects the momenta of every cluster of `rows` (equalities first, then inequalities from
// index `first_inequality`) that holds an inequality, at positions x.
bool ConstrainedIntegrator::reflect_clusters(System& system, const std::vector<Constraint>& rows,
                                             std::size_t first_inequality,
                                             const std::vector<Vec3>& x, std::vector<Vec3>& p,
                                             const AfterReflection* after,
                                             std::size_t first_new_row, const ChunkPass* then,
                                             std::size_t then_count, FurtherRounds* further) {
  const Particles& P = system.particles;
  // A lone contact (no other row in its cluster) in closed form, when reflect() would solve
  // the same single-row problem with H as its energy.
  const bool lone_rows_closed =
      energy_ == ReflectionEnergy::hamiltonian && reflection_ == ReflectionOperator::generalized;
  if (lone_rows_closed && first_inequality == 0) {
    return reflect_inequalities(system, rows, x, p, after, first_new_row, then, then_count,
                                further);
  }
  // Only the clusters holding an inequality are reflected: with the equality rows first (the
  // rods, prepared), found from the inequality rows alone. Clustering every row took the
  // default input's 1170 rods through find_clusters at each call (2 % of its loop on one
  // thread, 3.5 % of the calling thread's on two, serial).
  const bool prepared_first = first_inequality > 0 &&
                              first_inequality == constraints_.equalities.size() &&
                              equality_clusters_.prepared_for(P.size());
  const std::vector<Cluster> clusters =
      prepared_first ? equality_clusters_.clusters_holding(rows, first_inequality)
                     : find_clusters(rows, P.size());
  std::vector<bool> holds_inequality(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    holds_inequality[c] = clusters[c].rows.back() >= static_cast<std::int32_t>(first_inequality);
  }
  const bool any =
      std::find(holds_inequality.begin(), holds_inequality.end(), true) != holds_inequality.end();
  if (energy_ == ReflectionEnergy::shadow && any) {
    gather_hessian_blocks(system, clusters, holds_inequality);
  }
  reflection_terms_.reset(rows.size());
  const ReflectionTally tally{reflection_terms_, stats_};
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (!holds_inequality[c]) continue;
    const Cluster& cluster = clusters[c];
    const std::int32_t first_row = cluster.rows.front();
    const bool closed = lone_rows_closed && cluster.rows.size() == 1 &&
                        reflect_closed_form(system, rows[first_row], first_row, x, p, tally);
    if (!closed && energy_ == ReflectionEnergy::shadow) {
      const ShadowOperator shadow = shadow_operator(system, c, p);
      reflect_cluster(system, rows, first_inequality, cluster, x, p, &shadow, tally);
    } else if (!closed) {
      reflect_cluster(system, rows, first_inequality, cluster, x, p, nullptr, tally);
    }
    if (after) (*after)(0, cluster.particles.data(), cluster.particles.size());
  }
  reflection_terms_.add_to(step_virial_);
  return false;
}

bool ConstrainedIntegrator::reflect_closed_form(const System& system, const Constraint& row,
                                                std::int32_t index, const std::vector<Vec3>& x,
                                                std::vector<Vec3>& p, const ReflectionTally& tally,
                                                bool* settled) const {
  bool approaching = false;
  const double lambda = reflect_lone_row(row, x.data(), system.box, system.particles.mass,
                                         constraints_.tolerances.velocity, p.data(), &approaching);
  if (lambda < 0.0) return false;
  if (settled) *settled = !approaching;
  tally.add(index, pair_virial(row, lambda, x.data(), system.box));
  tally.stats.reflected += lambda > 0.0 ? 1 : 0;
  return true;
}

// Inequality rows alone (the contacts of a hard-sphere fluid): the rows' connected
// components (rows joined where they share a particle) are their clusters. A row alone in its
// component is reflected in closed form; the others' components through reflect(). The
// components share no particle, so any thread may reflect any of them with the same result, in
// any order; their virial terms are added in row order.
//
// Only the components that hold a row added since the last call (rows before first_new_row
// are its rows) or a row it left approaching are reflected: one whose rows the last call left
// all settled has the momenta it left and would not change. They are found by walking from
// those rows (GrowingRowComponents), the other rows not visited.
//
// Where the particle passes run in chunks, a chunk's thread reflects the components whose
// particles are in its chunk: their momenta are lines it holds (reflected by one thread,
// every other thread's lines crossed to its core and back within the step). A component
// across two chunks goes to one of them by its particles' parity, not to the lower: in a
// 4000-sphere fluid the lower chunk took 56 % of the rows and 59 % of the shared clusters,
// and the calling thread's share 7.1 ms of a run against 5.4 on the other thread. Fewer rows
// than a job is worth are reflected by the calling thread, unless `then` is given: the job
// then runs it as well, and it would be a job of its own after (the active set's later round:
// 3 rows a round, 7.5 us a call on the calling thread, bench/README.md, "Stop 70").
bool ConstrainedIntegrator::reflect_inequalities(System& system,
                                                 const std::vector<Constraint>& rows,
                                                 const std::vector<Vec3>& x, std::vector<Vec3>& p,
                                                 const AfterReflection* after,
                                                 std::size_t first_new_row, const ChunkPass* then,
                                                 std::size_t then_count, FurtherRounds* further) {
  const std::size_t n = system.particles.size();
  // Below this many rows to reflect a job's start (about a microsecond) costs more than the
  // rows' lines fetched from the other cores.
  constexpr std::size_t kSplitRows = 64;
  const int chunks = chunks_for_cheap(n);
  const auto slots = static_cast<std::size_t>(chunks);
  // The chunks' ends, as the particle passes split the particles.
  ChunkSlots<std::int32_t> chunk_end(slots);
  for (std::size_t c = 0; c < slots; ++c) {
    chunk_end[c] = static_cast<std::int32_t>(chunk_range(n, static_cast<int>(c), chunks).end);
  }
  auto chunk_of = [&](std::int32_t particle) {
    std::size_t c = 0;
    while (particle >= chunk_end[c]) ++c;
    return c;
  };
  auto owner = [&](std::int32_t a, std::int32_t b) {
    const std::size_t ca = chunk_of(a);
    if (b < 0) return ca;
    const std::size_t cb = chunk_of(b);
    return ((a + b) & 1) != 0 ? ca : cb;
  };
  // The seeds: the rows the last call left approaching, then the rows added (implicit where
  // the chunks' threads walk: rows [first_new, rows.size())).
  std::vector<std::int32_t>& seeds = reflection_seeds_;
  seeds.clear();
  std::size_t first_new = first_new_row;
  if (!row_components_.continues(n, first_new_row)) {
    row_components_.restart(n);
    first_new = 0;
  } else {
    for (const OnItsOwnLine<std::vector<std::int32_t>>& unsettled : unsettled_of_chunk_) {
      seeds.insert(seeds.end(), unsettled.value.begin(), unsettled.value.end());
    }
  }
  unsettled_of_chunk_.resize(slots);
  for (OnItsOwnLine<std::vector<std::int32_t>>& unsettled : unsettled_of_chunk_) {
    unsettled.value.clear();
  }
  reflection_chunks_.resize(slots);
  for (OnItsOwnLine<ReflectionChunk>& chunk : reflection_chunks_) {
    chunk.value.lone_rows.clear();
    chunk.value.clusters_used = 0;
  }
  // A component's particles, ascending (as find_clusters makes them and reflect() reads them),
  // into `particles`.
  auto particles_of = [&](const std::int32_t* found, std::size_t count,
                          std::vector<std::int32_t>& particles) {
    particles.clear();
    for (std::size_t k = 0; k < count; ++k) {
      const Constraint& row = rows[static_cast<std::size_t>(found[k])];
      particles.push_back(row.i);
      if (row.j >= 0) particles.push_back(row.j);
    }
    std::sort(particles.begin(), particles.end());
    particles.erase(std::unique(particles.begin(), particles.end()), particles.end());
  };
  // A component of several rows (`particles`: particles_of's) into chunk c's clusters, its
  // rows ascending.
  auto add_cluster = [&](std::size_t c, const std::vector<std::int32_t>& particles,
                         const std::int32_t* found, std::size_t count) {
    ReflectionChunk& chunk = reflection_chunks_[c].value;
    if (chunk.clusters_used == chunk.clusters.size()) chunk.clusters.emplace_back();
    Cluster& cluster = chunk.clusters[chunk.clusters_used++];
    cluster.particles.assign(particles.begin(), particles.end());
    cluster.rows.assign(found, found + count);
    std::sort(cluster.rows.begin(), cluster.rows.end());
  };
  reflection_terms_.reset(rows.size());
  reflection_stats_.assign(slots, OnItsOwnLine<ConstraintStatistics>{});
  auto reflect_chunk = [&](std::size_t c) {
    const ReflectionTally tally{reflection_terms_, reflection_stats_[c].value};
    const int chunk = static_cast<int>(c);
    std::vector<std::int32_t>& unsettled = unsettled_of_chunk_[c].value;
    const ReflectionChunk& own = reflection_chunks_[c].value;
    for (const std::int32_t r : own.lone_rows) {
      const Constraint& row = rows[static_cast<std::size_t>(r)];
      bool left_settled = false;
      if (!reflect_closed_form(system, row, r, x, p, tally, &left_settled)) {
        Cluster cluster;  // a row without a closed form (no direction): the general reflection
        cluster.particles.push_back(row.i);
        if (row.j >= 0) cluster.particles.push_back(row.j);
        std::sort(cluster.particles.begin(), cluster.particles.end());
        cluster.rows.push_back(r);
        left_settled = reflect_cluster(system, rows, 0, cluster, x, p, nullptr, tally);
      }
      if (!left_settled) unsettled.push_back(r);
      if (after) {
        const std::int32_t particles[2] = {row.i, row.j};
        (*after)(chunk, particles, row.j >= 0 ? 2 : 1);
      }
    }
    for (std::size_t k = 0; k < own.clusters_used; ++k) {
      const Cluster& cluster = own.clusters[k];
      if (!reflect_cluster(system, rows, 0, cluster, x, p, nullptr, tally)) {
        unsettled.insert(unsettled.end(), cluster.rows.begin(), cluster.rows.end());
      }
      if (after) (*after)(chunk, cluster.particles.data(), cluster.particles.size());
    }
  };
  if (chunks > 1 && then) {
    // The job is the test's own (the active set's next): the rows are linked, walked and
    // reflected in it too, each chunk's thread linking the rows' ends at its own particles,
    // then walking from the seeds it owns (the row's owner, as for a lone row) to their
    // components. A component is reflected by the owner of its lowest seed, whichever thread
    // found it first. On the calling thread before the job, the link and the walk were a third
    // of its time alone in the 4000-sphere fluid's active set (bench/README.md, "Stop 73").
    // With `further`, the active set's next rounds follow in the same job while they find rows.
    std::size_t round_first_new = first_new;
    // Which rows are seeds: those at or past round_first_new, and those marked with this
    // round's number (the last round's rows it left approaching, in `seeds`).
    auto mark_seeds = [&] {
      row_components_.begin_link(rows.size());
      seed_mark_.resize(rows.size(), 0);
      if (++seed_call_ == 0) {
        std::fill(seed_mark_.begin(), seed_mark_.end(), 0);
        seed_call_ = 1;
      }
      for (const std::int32_t r : seeds) seed_mark_[static_cast<std::size_t>(r)] = seed_call_;
    };
    mark_seeds();
    auto seed = [&](std::int32_t r) {
      return static_cast<std::size_t>(r) >= round_first_new ||
             seed_mark_[static_cast<std::size_t>(r)] == seed_call_;
    };
    auto row_owner = [&](std::int32_t r) {
      const Constraint& row = rows[static_cast<std::size_t>(r)];
      return owner(row.i, row.j);
    };
    ChunkSlots<IndexRange> then_range(slots);
    for (std::size_t c = 0; c < slots; ++c) {
      then_range[c] = chunk_range(then_count, static_cast<int>(c), chunks);
    }
    const auto link = [&](int c) {
      const std::int32_t begin = c == 0 ? 0 : chunk_end[static_cast<std::size_t>(c) - 1];
      row_components_.link_ends_at(rows, begin, chunk_end[static_cast<std::size_t>(c)]);
    };
    const auto walk_and_reflect = [&](int chunk) {
      const auto c = static_cast<std::size_t>(chunk);
      ReflectionChunk& own = reflection_chunks_[c].value;
      own.seeds.clear();
      for (const std::int32_t r : seeds) {
        if (row_owner(r) == c) own.seeds.push_back(r);
      }
      for (std::size_t r = round_first_new; r < rows.size(); ++r) {
        if (row_owner(static_cast<std::int32_t>(r)) == c) {
          own.seeds.push_back(static_cast<std::int32_t>(r));
        }
      }
      row_components_.components_of(
          own.walker, own.seeds.data(), own.seeds.size(),
          [&](const std::int32_t* found, std::size_t count) {
            if (count == 1) {
              own.lone_rows.push_back(found[0]);  // the seed, its own lowest
              return;
            }
            std::int32_t lowest = std::numeric_limits<std::int32_t>::max();
            for (std::size_t k = 0; k < count; ++k) {
              if (seed(found[k])) lowest = std::min(lowest, found[k]);
            }
            if (row_owner(lowest) != c) return;
            particles_of(found, count, own.particles);
            add_cluster(c, own.particles, found, count);
          });
      reflect_chunk(c);
    };
    const auto test = [&](int c) {
      const IndexRange range = then_range[static_cast<std::size_t>(c)];
      (*then)(c, range.begin, range.end);
    };
    // Between rounds, on one thread while the others wait: the round's figures taken, the
    // caller's start (the next round's rows joined), and that round's seeds (the rows this one
    // left approaching and the rows joined) marked, its rows linked (a few: on one thread, a
    // barrier fewer) and the chunks' lists emptied.
    const auto next_round = [&] {
      reflection_terms_.add_to(step_virial_);
      for (const OnItsOwnLine<ConstraintStatistics>& figures : reflection_stats_) {
        stats_.add(figures.value);
      }
      const std::size_t before = rows.size();
      further->start();
      row_components_.end_link(before);
      round_first_new = before;
      seeds.clear();
      for (OnItsOwnLine<std::vector<std::int32_t>>& unsettled : unsettled_of_chunk_) {
        seeds.insert(seeds.end(), unsettled.value.begin(), unsettled.value.end());
        unsettled.value.clear();
      }
      for (OnItsOwnLine<ReflectionChunk>& chunk : reflection_chunks_) {
        chunk.value.lone_rows.clear();
        chunk.value.clusters_used = 0;
      }
      mark_seeds();
      row_components_.link_ends_at(rows, 0, static_cast<std::int32_t>(n));
      reflection_terms_.reset(rows.size());
      reflection_stats_.assign(slots, OnItsOwnLine<ConstraintStatistics>{});
    };
    // Each chunk's first exception; one from next_round ends the job as well.
    ChunkSlots<std::exception_ptr> failed(slots);
    std::exception_ptr round_failed;
    // body(c) for this thread's chunks, then (`barrier`) the barrier: whether every chunk
    // went through, which every thread then reads alike (written before the barrier).
    auto phase = [&](int thread, int threads, const auto& body, bool barrier) {
      for (int c = thread; c < chunks; c += threads) {
        try {
          body(c);
        } catch (...) {
          failed[static_cast<std::size_t>(c)] = std::current_exception();
        }
      }
      if (!barrier) return false;
      team_barrier();
      return std::none_of(failed.begin(), failed.end(),
                          [](const std::exception_ptr& e) { return e != nullptr; });
    };
    const auto start_walk_and_reflect = [&](int c) {
      further->start_chunk(c);
      walk_and_reflect(c);
    };
    auto job = [&](int thread, int threads) {
      if (!phase(thread, threads, link, true) || !phase(thread, threads, walk_and_reflect, true) ||
          !phase(thread, threads, test, further != nullptr)) {
        return;
      }
      // Each thread's own count: next_round changes nothing follows() reads, and a thread may
      // still be asking while thread 0 has begun the round.
      for (int followed = 0; further->follows(followed); ++followed) {
        if (thread == 0) {
          try {
            next_round();
          } catch (...) {
            round_failed = std::current_exception();
          }
        }
        team_barrier();
        if (round_failed || !phase(thread, threads, start_walk_and_reflect, true) ||
            !phase(thread, threads, test, true)) {
          return;
        }
      }
    };
    run_on_team(std::min(chunks, thread_count()), job);
    if (round_failed) std::rethrow_exception(round_failed);
    for (const std::exception_ptr& e : failed) {
      if (e) std::rethrow_exception(e);
    }
    row_components_.end_link(rows.size());
  } else {
    row_components_.link(rows);
    for (std::size_t r = first_new; r < rows.size(); ++r) {
      seeds.push_back(static_cast<std::int32_t>(r));
    }
    std::size_t work = 0;  // the rows to reflect
    row_components_.components_of(
        seeds.data(), seeds.size(), [&](const std::int32_t* found, std::size_t count) {
          work += count;
          if (count == 1) {
            const Constraint& row = rows[static_cast<std::size_t>(found[0])];
            reflection_chunks_[owner(row.i, row.j)].value.lone_rows.push_back(found[0]);
            return;
          }
          std::vector<std::int32_t>& particles = component_particles_;
          particles_of(found, count, particles);
          add_cluster(owner(particles.front(), particles.back()), particles, found, count);
        });
    if (chunks > 1 && work >= kSplitRows) {
      for_each_chunk(slots, chunks, [&](int c, std::size_t, std::size_t) {
        reflect_chunk(static_cast<std::size_t>(c));
      });
    } else {
      for (std::size_t c = 0; c < slots; ++c) reflect_chunk(c);
    }
  }
  reflection_terms_.add_to(step_virial_);
  for (const OnItsOwnLine<ConstraintStatistics>& figures : reflection_stats_) {
    stats_.add(figures.value);
  }
  return chunks > 1 && then;
}

bool ConstrainedIntegrator::reflect_cluster(const System& system,
                                            const std::vector<Constraint>& rows,
                                            std::size_t first_inequality, const Cluster& cluster,
                                            const std::vector<Vec3>& x, std::vector<Vec3>& p,
                                            const ShadowOperator* shadow,
                                            const ReflectionTally& tally) const {
  const Particles& P = system.particles;
  // Kept by each thread between calls (a hard-sphere fluid reflects a few small clusters a
  // step, on every thread): their storage, not their values.
  struct Scratch {
    LocalCluster local;
    std::vector<bool> equality;
    std::vector<Vec3> p_local, x_local;
  };
  thread_local Scratch scratch;
  LocalCluster& local = scratch.local;
  localize(cluster, rows, P.mass, local);
  std::vector<bool>& equality = scratch.equality;
  equality.clear();
  for (std::int32_t r : cluster.rows)
    equality.push_back(r < static_cast<std::int32_t>(first_inequality));
  std::vector<Vec3>& p_local = scratch.p_local;
  gather(p, cluster.particles, p_local);
  std::vector<Vec3>& x_local = scratch.x_local;
  gather(x, cluster.particles, x_local);
  const ReflectionStats r = reflect(local, equality, x_local, p_local, system.box, reflection_,
                                    constraints_.tolerances.velocity, constraints_.limits, shadow);
  for (std::size_t k = 0; k < local.rows.size(); ++k) {
    tally.add(local.global_rows[k],
              pair_virial(local.rows[k], r.row_impulse[k], x_local.data(), system.box));
  }
  tally.stats.reflected += r.reflected;
  tally.stats.shadow_fallbacks += r.shadow_fallbacks;
  tally.stats.stalled += r.capped ? 1 : 0;
  tally.stats.cycled += r.cycled ? 1 : 0;
  tally.stats.qp_caps += r.qp_caps;
  scatter(p_local, cluster.particles, p);
  return r.settled;
}

void ConstrainedIntegrator::finish_step() {
  for (std::size_t k = 0; k < sampled_.size(); ++k) {
    sampled_[k].add(stats_);
    virial_sums_[k] += step_virial_ / dt_;
  }
  stats_ = ConstraintStatistics{};
}

std::vector<Constraint> ConstrainedIntegrator::candidates_for_step(System& system,
                                                                   std::vector<Vec3>& q,
                                                                   std::vector<Vec3>& x) {
  if (engine_.neighbors().cutoff() > 0 && !engine_.neighbors_cover(x)) {
    engine_.ensure_neighbors(system, true);
    // The rebuild wrapped the positions into the periodic box: q and x move with them.
    const std::vector<Vec3>& wrapped = system.particles.position;
    for (std::size_t i = 0; i < q.size(); ++i) {
      x[i] += wrapped[i] - q[i];
      q[i] = wrapped[i];
    }
    if (!engine_.neighbors_cover(x)) {
      throw SimulationError("step " + std::to_string(system.step + 1) +
                            ": a particle would move more than half the neighbour skin in one "
                            "step; increase [neighbor] skin or reduce the timestep");
    }
  }
  double largest = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) largest = std::max(largest, norm(x[i] - q[i]));
  return constraints_.nearby_inequalities(system.particles, q.data(), engine_.neighbors(),
                                          system.box,
                                          4.0 * largest + 2.0 * constraints_.tolerances.gap);
}

void ConstrainedIntegrator::record_geometry(const System& system,
                                            const std::vector<Constraint>& candidates, bool full,
                                            const double* candidates_smallest, bool projected) {
  const Particles& P = system.particles;
  double gap = full
                   ? constraints_.minimum_gap(P, P.position.data(), engine_.neighbors(), system.box)
                   : std::numeric_limits<double>::infinity();
  if (candidates_smallest) {
    gap = std::min(gap, *candidates_smallest);
  } else {
    // Per chunk of candidates, each bounded by its own running minimum: a row beyond that
    // bound is beyond the overall minimum too, and every gap below it is evaluated exactly,
    // so the minimum is the serial loop's on any number of threads.
    const int chunks = chunks_for_cheap(candidates.size());
    std::vector<double> chunk_gap(static_cast<std::size_t>(chunks), gap);
    for_each_chunk(candidates.size(), chunks, [&](int c, std::size_t begin, std::size_t end) {
      double smallest = chunk_gap[static_cast<std::size_t>(c)];
      for (std::size_t k = begin; k < end; ++k) {
        smallest = std::min(
            smallest, gap_unless_beyond(candidates[k], P.position.data(), system.box, smallest));
      }
      chunk_gap[static_cast<std::size_t>(c)] = smallest;
    });
    for (const double smallest : chunk_gap) gap = std::min(gap, smallest);
  }
  stats_.min_gap = std::min(stats_.min_gap, gap);
  if (gap < -constraints_.tolerances.gap) ++stats_.penetrations;
  stats_.max_rod_violation = projected && projected_deviation_ >= 0.0
                                 ? std::max(stats_.max_rod_violation, projected_deviation_)
                                 : largest_rod_violation(system, stats_.max_rod_violation);
}

// Per equality cluster: a chain's rod lengths are those its momentum projection computed at
// these positions (the end of the step), when they are still these positions; otherwise,
// and for other clusters, gap_of. A maximum, so the clusters' order and chunks change no bit.
double ConstrainedIntegrator::largest_rod_violation(const System& system, double start) {
  const std::vector<Constraint>& rods = constraints_.equalities;
  if (rods.empty()) return start;
  if (!equality_clusters_.prepared_for(system.particles.size())) {
    equality_clusters_.prepare(rods, system.particles.mass);
  }
  const std::vector<PreparedCluster>& clusters = equality_clusters_.all();
  const Vec3* x = system.particles.position.data();
  const int chunks = chunks_for_work(clusters.size(), rods.size());
  if (chain_works_.size() < static_cast<std::size_t>(chunks)) chain_works_.resize(chunks);
  std::vector<double> chunk_largest(static_cast<std::size_t>(chunks), start);
  for_each_chunk(clusters.size(), chunks, [&](int c, std::size_t begin, std::size_t end) {
    double largest = start;
    for (std::size_t index = begin; index < end; ++index) {
      const PreparedCluster& prepared = clusters[index];
      if (prepared.chain) {
        largest = prepared.chain->largest_relative_deviation(
            x, system.box, chain_works_[static_cast<std::size_t>(c)], largest);
        continue;
      }
      for (const std::int32_t r : prepared.cluster.rows) {
        largest = std::max(largest, std::abs(gap_of(rods[r], x, system.box)) / rods[r].length);
      }
    }
    chunk_largest[static_cast<std::size_t>(c)] = largest;
  });
  double largest = start;
  for (const double l : chunk_largest) largest = std::max(largest, l);
  return largest;
}

void ConstraintStatistics::add(const ConstraintStatistics& later) {
  steps += later.steps;
  active += later.active;
  reflected += later.reflected;
  smooth += later.smooth;
  stalled += later.stalled;
  cycled += later.cycled;
  penetrations += later.penetrations;
  fallbacks += later.fallbacks;
  deficits += later.deficits;
  shadow_fallbacks += later.shadow_fallbacks;
  solves += later.solves;
  solver_iterations += later.solver_iterations;
  max_solver_iterations = std::max(max_solver_iterations, later.max_solver_iterations);
  min_gap = std::min(min_gap, later.min_gap);
  max_rod_violation = std::max(max_rod_violation, later.max_rod_violation);
  active_set_caps += later.active_set_caps;
  feasibility_caps += later.feasibility_caps;
  qp_caps += later.qp_caps;
  contact_time_caps += later.contact_time_caps;
  relative_restorations += later.relative_restorations;
}

void ConstraintStatistics::save(std::vector<double>& out) const {
  for (std::int64_t count : {steps, active, reflected, smooth, stalled, cycled, penetrations,
                             fallbacks, deficits, shadow_fallbacks, solves, solver_iterations}) {
    out.push_back(static_cast<double>(count));
  }
  out.push_back(max_solver_iterations);
  out.push_back(min_gap);
  out.push_back(max_rod_violation);
  for (std::int64_t count : {active_set_caps, feasibility_caps, qp_caps, contact_time_caps}) {
    out.push_back(static_cast<double>(count));
  }
  out.push_back(static_cast<double>(relative_restorations));
}

ConstraintStatistics ConstraintStatistics::load(const double* in, std::size_t size) {
  ConstraintStatistics s;
  for (std::int64_t* count :
       {&s.steps, &s.active, &s.reflected, &s.smooth, &s.stalled, &s.cycled, &s.penetrations,
        &s.fallbacks, &s.deficits, &s.shadow_fallbacks, &s.solves, &s.solver_iterations}) {
    *count = static_cast<std::int64_t>(*in++);
  }
  s.max_solver_iterations = static_cast<int>(*in++);
  s.min_gap = *in++;
  s.max_rod_violation = *in++;
  if (size == saved_size_without_caps) return s;
  for (std::int64_t* count :
       {&s.active_set_caps, &s.feasibility_caps, &s.qp_caps, &s.contact_time_caps}) {
    *count = static_cast<std::int64_t>(*in++);
  }
  if (size == saved_size_without_relative) return s;
  s.relative_restorations = static_cast<std::int64_t>(*in++);
  return s;
}

// Layout: the two samplers' statistics and virial sums, then the previous step's positions
// (the linearisation point of linearised constraints).
std::vector<double> ConstrainedIntegrator::saved_state() const {
  std::vector<double> out;
  for (const ConstraintStatistics& s : sampled_) s.save(out);
  out.insert(out.end(), virial_sums_.begin(), virial_sums_.end());
  for (const Vec3& x : previous_positions_) out.insert(out.end(), {x.x, x.y, x.z});
  return out;
}

std::vector<double> ConstrainedIntegrator::state_in_order(
    const std::vector<double>& state, const std::vector<std::int32_t>& order) const {
  // The statistics and virial sums, then (linearised rows) each particle's previous position.
  const std::size_t head = 2 * ConstraintStatistics::saved_size + 2;
  if (state.size() != head + 3 * order.size()) return state;
  std::vector<double> out(state.begin(), state.begin() + static_cast<std::ptrdiff_t>(head));
  append_triples_in_order(state.data() + head, order, out);
  return out;
}

void ConstrainedIntegrator::restore_state(const std::vector<double>& state, const System& system) {
  const std::size_t n = system.particles.size();
  // The current layout, or that of a checkpoint written by an earlier deli.
  std::size_t stats_size = ConstraintStatistics::saved_size;
  for (std::size_t size :
       {ConstraintStatistics::saved_size, ConstraintStatistics::saved_size_without_relative,
        ConstraintStatistics::saved_size_without_caps}) {
    const std::size_t head = 2 * size + 2;
    if (state.size() == head || state.size() == head + 3 * n) {
      stats_size = size;
      break;
    }
    if (size == ConstraintStatistics::saved_size_without_caps) {
      throw InputError("the checkpoint's integrator state (" + std::to_string(state.size()) +
                       " numbers) is not that of '" + name() + "' for " + std::to_string(n) +
                       " atoms; restart with the input that wrote it");
    }
  }
  const std::size_t head = 2 * stats_size + 2;
  for (std::size_t k = 0; k < sampled_.size(); ++k) {
    sampled_[k] = ConstraintStatistics::load(&state[k * stats_size], stats_size);
    virial_sums_[k] = state[2 * stats_size + k];
  }
  previous_positions_.clear();
  for (std::size_t i = head; i < state.size(); i += 3) {
    previous_positions_.push_back({state[i], state[i + 1], state[i + 2]});
  }
}

double ConstrainedIntegrator::take_constraint_virial(Sampler sampler, bool keep) {
  const auto k = static_cast<std::size_t>(sampler);
  const std::int64_t steps = sampled_[k].steps;
  const double average = steps > 0 ? virial_sums_[k] / static_cast<double>(steps) : 0.0;
  if (!keep) virial_sums_[k] = 0.0;
  return average;
}

std::vector<std::pair<std::string, double>> ConstrainedIntegrator::take_statistics(Sampler sampler,
                                                                                   bool keep) {
  const auto k = static_cast<std::size_t>(sampler);
  const ConstraintStatistics s = sampled_[k];
  if (!keep) sampled_[k] = ConstraintStatistics{};
  const double steps = std::max<double>(1.0, static_cast<double>(s.steps));
  // +inf when no inequality row was within reach over the span (no contact to measure).
  return {{"min_gap", s.min_gap},
          {"max_rod_violation", s.max_rod_violation},
          {"active_per_step", static_cast<double>(s.active) / steps},
          {"reflected", static_cast<double>(s.reflected)},
          {"smooth_per_step", static_cast<double>(s.smooth) / steps},
          {"stalled_reflections", static_cast<double>(s.stalled)},
          {"cycled_reflections", static_cast<double>(s.cycled)},
          {"penetrating_steps", static_cast<double>(s.penetrations)},
          {"landings", static_cast<double>(s.fallbacks)},
          {"landing_deficits", static_cast<double>(s.deficits)},
          {"relative_restorations", static_cast<double>(s.relative_restorations)},
          {"shadow_fallbacks", static_cast<double>(s.shadow_fallbacks)},
          {"solver_iterations_mean",
           s.solves > 0 ? static_cast<double>(s.solver_iterations) / static_cast<double>(s.solves)
                        : 0.0},
          {"solver_iterations_max", static_cast<double>(s.max_solver_iterations)},
          {"active_set_caps", static_cast<double>(s.active_set_caps)},
          {"feasibility_caps", static_cast<double>(s.feasibility_caps)},
          {"qp_caps", static_cast<double>(s.qp_caps)},
          {"contact_time_caps", static_cast<double>(s.contact_time_caps)}};
}

}  // namespace deli
