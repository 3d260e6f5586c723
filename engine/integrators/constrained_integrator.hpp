#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>

#include "constraints/clusters.hpp"
#include "constraints/constraint_set.hpp"
#include "constraints/row_components.hpp"
#include "constraints/row_stretches.hpp"
#include "core/cache_line.hpp"
#include "core/ordered_terms.hpp"
#include "integrators/integrator.hpp"
#include "integrators/reflection.hpp"
#include "integrators/shadow_pairs.hpp"
#include "solvers/prepared_clusters.hpp"

namespace deli {

// Counters over a span of steps (one step, or the steps between two samples).
struct ConstraintStatistics {
  std::int64_t steps = 0;
  std::int64_t active = 0;            // rows in the extended active sets (or contact events)
  std::int64_t reflected = 0;         // rows that received a reflection impulse
  std::int64_t smooth = 0;            // rows in the smooth sets
  std::int64_t stalled = 0;           // reflections capped or stalled
  std::int64_t cycled = 0;            // reflections that cycled (ended inelastically)
  std::int64_t penetrations = 0;      // steps ending with an inequality below -tolerance
  std::int64_t fallbacks = 0;         // rows the feasibility guard landed
  std::int64_t deficits = 0;          // landings whose energy could not be restored
  std::int64_t shadow_fallbacks = 0;  // shadow-H solves that fell back to H
  std::int64_t solves = 0, solver_iterations = 0;
  int max_solver_iterations = 0;
  double min_gap = std::numeric_limits<double>::infinity();
  double max_rod_violation = 0;  // |f| / length, equality rows
  // Iteration limits hit where the step goes on (SolverLimits says what each does).
  std::int64_t active_set_caps = 0;    // steps whose active set was still growing
  std::int64_t feasibility_caps = 0;   // steps whose guard still had overlapped rows
  std::int64_t qp_caps = 0;            // reflection QP solves ended unconverged
  std::int64_t contact_time_caps = 0;  // contact times left unbracketed (collision)
  // Landings whose excess energy was taken from the motion relative to the rigid motion
  // (impact_time), the touched rows' normal motion holding too little.
  std::int64_t relative_restorations = 0;

  void add(const ConstraintStatistics& later);
  // As numbers for a checkpoint (counts are exact in a double up to 2^53).
  void save(std::vector<double>& out) const;
  static constexpr std::size_t saved_size = 20;
  // Layouts of checkpoints of an earlier deli, whose missing counters load as 0: before
  // relative_restorations, and before the limit counters too.
  static constexpr std::size_t saved_size_without_relative = 19;
  static constexpr std::size_t saved_size_without_caps = 15;
  static ConstraintStatistics load(const double* in, std::size_t size = saved_size);
};

// What every integrator of constrained systems shares (GVI, the direct-substitution and
// collision baselines): the constraint set and the force engine, the position update
// solved cluster by cluster (failures reported with the problem dumped), the momentum
// projection, reflections (H or Verlet's shadow H), the statistics and constraint virial
// per sampler, and the checkpointed state. Each integrator writes only its step.
class ConstrainedIntegrator : public Integrator {
 public:
  double timestep() const override { return dt_; }
  // Puts the state on the constraint manifold (positions, then momenta) and computes forces.
  void setup(System& system) override;
  ForceEngine& engine() override { return engine_; }
  const ForceEngine& forces() const override { return engine_; }
  std::vector<std::pair<std::string, double>> take_statistics(Sampler sampler = Sampler::thermo,
                                                              bool keep = false) override;
  double take_constraint_virial(Sampler sampler = Sampler::thermo, bool keep = false) override;
  std::vector<double> saved_state() const override;
  std::vector<double> state_in_order(const std::vector<double>& state,
                                     const std::vector<std::int32_t>& order) const override;
  void restore_state(const std::vector<double>& state, const System& system) override;
  // RATTLE's velocity projection onto the equality rows; its impulses count in no virial.
  void project_velocities(System& system) override;

  const ConstraintSet& constraints() const { return constraints_; }

 protected:
  ConstrainedIntegrator(const ForceField& force_field, ConstraintSet constraints, double timestep,
                        double skin, ReflectionOperator reflection, ReflectionEnergy energy,
                        const Particles& particles);

  // Solves x = q + delta + h M^-1 C(q) z with f(x) = 0 for the equality rows and
  // 0 <= z _|_ g(x) >= 0 for the rest, per cluster; returns the impulses C z per particle in
  // `impulse` and their virial. Gradients are taken at `q`.
  // With `delta_changed` (only for the equality rows themselves, all held): the clusters
  // none of whose particles has a changed delta since the last such call at the same q are
  // not solved again; their impulses are left as that call wrote them, and its solver
  // iterations count again (the statistics are those of solving them again).
  // With `solved` (any rows, the same q as the last call on the equality rows alone): a
  // chain of rods left a cluster of its own whose delta equals, particle for particle and
  // bit for bit, the delta that call solved it for takes that call's impulses
  // (`solved->impulse`), virial and iteration count instead of being solved again.
  // A chain's virial is summed on its own, then added. Every particle of the rows' clusters
  // gets its impulse written (or, with `delta_changed`, kept); the others' are not touched.
  // The equality rows passed as themselves (rows is constraints_.equalities) are all held:
  // `equality` is all true then.
  struct SolvedEqualities {
    const std::vector<Vec3>& delta;
    const std::vector<Vec3>& impulse;
  };
  // The particles of one or more clusters: list[0..count) where list is not null, else
  // first..first+count-1 (consecutive clusters joined into one run: one range for the vector
  // passes).
  struct ParticleRun {
    const std::int32_t* list;
    std::size_t first, count;
    // body(begin, end) over ranges of consecutive particles that make up the run (one range
    // a particle for a list).
    template <class Body>
    void for_each_range(Body&& body) const {
      if (list) {
        for (std::size_t k = 0; k < count; ++k) {
          const auto i = static_cast<std::size_t>(list[k]);
          body(i, i + 1);
        }
        return;
      }
      body(first, first + count);
    }
  };
  // Per-particle passes made with the cluster solves, chunk by chunk on the thread that
  // solves the chunk's clusters (no parallel region, and no pass over every particle, of
  // their own): before(chunk, run) over the chunk's clusters' particles before any of them
  // is solved (it makes what their solves read), after(chunk, run) once all are (it reads
  // what they wrote). Chunks are numbered from 0, below thread_count().
  struct ClusterPasses {
    std::function<void(int, const ParticleRun&)> before, after;
  };
  double solve_positions(System& system, const std::vector<Constraint>& rows,
                         const std::vector<bool>& equality, const std::vector<Vec3>& q,
                         const std::vector<Vec3>& delta, std::vector<Vec3>& impulse,
                         const std::vector<char>* delta_changed = nullptr,
                         const SolvedEqualities* solved = nullptr,
                         const ClusterPasses* passes = nullptr);
  // The pair Hessian blocks touching the clusters marked `reflected`, in one scan; then
  // shadow_operator(..., c, p) is cluster c's shadow-energy operator.
  void gather_hessian_blocks(const System& system, const std::vector<Cluster>& clusters,
                             const std::vector<bool>& reflected);
  ShadowOperator shadow_operator(const System& system, std::size_t c,
                                 const std::vector<Vec3>& p) const;
  // Called with each reflected cluster's particles once the cluster is reflected, on the
  // thread that reflected it; `chunk` (below thread_count()) numbers that thread's share.
  using AfterReflection =
      std::function<void(int chunk, const std::int32_t* particles, std::size_t count)>;
  // Reflects the momenta of every cluster of `rows` (equalities first, then inequalities from
  // index `first_inequality`) that holds an inequality, at positions x. Rows before
  // `first_new_row` are the last call's rows, the momenta changed since by that call alone: a
  // cluster of those rows alone that it left with no row approaching would not change, and
  // is passed over (in reflect_inequalities).
  // Given `then`, where the reflections run in a job of the team (reflect_inequalities, with
  // as many chunks as a loop over `then_count` rows read after a pass over the particles):
  // then(c, begin, end) for those chunks in the same job, once every reflection (and `after`)
  // is done, each on the thread of the reflections' chunk c; returns whether it ran.
  using ChunkPass = std::function<void(int chunk, std::size_t begin, std::size_t end)>;
  // The active set's later rounds in the same job, where `then` runs there: once `then` has
  // ended on every chunk, every thread asks follows(followed), `followed` the rounds that have
  // followed in the job so far (the same answer on each: it reads what the chunks wrote
  // before). Where a round follows, start() on one thread appends its rows to the rows
  // reflected (`rows`, which grows) and readies the passes for its reflections; it must leave
  // what follows() reads as it is, as the other threads may still be reading it. Then, once
  // every thread has, start_chunk(c) on each chunk's thread, its reflections and `then`.
  struct FurtherRounds {
    std::function<bool(int followed)> follows;
    std::function<void()> start;
    std::function<void(int chunk)> start_chunk;
  };
  bool reflect_clusters(System& system, const std::vector<Constraint>& rows,
                        std::size_t first_inequality, const std::vector<Vec3>& x,
                        std::vector<Vec3>& p, const AfterReflection* after = nullptr,
                        std::size_t first_new_row = 0, const ChunkPass* then = nullptr,
                        std::size_t then_count = 0, FurtherRounds* further = nullptr);
  // Where reflections leave their figures: the virial's terms by row of the rows reflected
  // (added to the step's virial in row order), and the counters (one set per thread where
  // reflections run on several).
  struct ReflectionTally {
    TermsByRow& terms;
    ConstraintStatistics& stats;
    void add(std::int32_t row, double term) const {
      terms.set(static_cast<std::size_t>(row), term);
    }
  };
  // Parts of reflect_clusters: one cluster through reflect(); one row in closed form (false,
  // with nothing done, where it has none); rows without equalities, with closed forms.
  // reflect_cluster returns ReflectionStats::settled.
  bool reflect_cluster(const System& system, const std::vector<Constraint>& rows,
                       std::size_t first_inequality, const Cluster& cluster,
                       const std::vector<Vec3>& x, std::vector<Vec3>& p,
                       const ShadowOperator* shadow, const ReflectionTally& tally) const;
  // reflect_closed_form's `row` is row `index` of the rows reflected; `settled`: the row left
  // not approaching.
  bool reflect_closed_form(const System& system, const Constraint& row, std::int32_t index,
                           const std::vector<Vec3>& x, std::vector<Vec3>& p,
                           const ReflectionTally& tally, bool* settled = nullptr) const;
  bool reflect_inequalities(System& system, const std::vector<Constraint>& rows,
                            const std::vector<Vec3>& x, std::vector<Vec3>& p,
                            const AfterReflection* after, std::size_t first_new_row,
                            const ChunkPass* then, std::size_t then_count, FurtherRounds* further);
  // Projects the momenta p onto the rows' tangent space at x, cluster by cluster (`passes`
  // as for solve_positions); returns the projection's virial.
  double project_momenta(System& system, const std::vector<Constraint>& rows,
                         const std::vector<Vec3>& x, std::vector<Vec3>& p,
                         const ClusterPasses* passes = nullptr);
  // The inequality rows a step from q (the system's positions) towards x (the
  // unconstrained end, say) can close: those within four times its largest displacement.
  // Rebuilds the neighbour list first if x leaves it, which wraps the positions into a
  // periodic box: q and x are then moved with them. Fails if even a fresh list cannot cover
  // the step.
  std::vector<Constraint> candidates_for_step(System& system, std::vector<Vec3>& q,
                                              std::vector<Vec3>& x);
  // `candidates_smallest`, when given, is the smallest gap of the candidates at the current
  // positions, already found: the candidates are not scanned again. `projected`: the last
  // project_momenta was at the current positions (nothing has moved them since), so the rod
  // lengths its chain kernels measured there stand for the largest rod violation.
  void record_geometry(const System& system, const std::vector<Constraint>& candidates, bool full,
                       const double* candidates_smallest = nullptr, bool projected = false);
  // max |f| / length over the equality rows at the current positions, at least `start`.
  double largest_rod_violation(const System& system, double start);
  // The implicit midpoint's fixed point, the one loop of every integrator that has one:
  // repeats `pass` (one pass, returning the largest change it made, sigma) until a pass
  // from the `first_checked`-th on changes less than the solver tolerance; at
  // limits.midpoint_passes passes the run stops with the step and the last change.
  template <class Pass>
  void iterate_midpoint(const System& system, int first_checked, Pass&& pass) const {
    for (int k = 0;; ++k) {
      const double change = pass();
      if (change <= constraints_.tolerances.solver && k >= first_checked) return;
      if (k + 1 >= std::max(constraints_.limits.midpoint_passes, first_checked + 1)) {
        midpoint_failure(system, change);
      }
    }
  }
  [[noreturn]] void midpoint_failure(const System& system, double change) const;
  // Clusters the rows (the equality rows themselves: their prepared clusters; else
  // find_clusters into found_clusters_) and returns how many; prepared_cluster(rows, k) is
  // then cluster k's prepared form when it is one of the equality clusters, else null.
  std::size_t cluster_rows(const std::vector<Constraint>& rows, const Particles& particles);
  const PreparedCluster* prepared_cluster(const std::vector<Constraint>& rows,
                                          std::size_t index) const;
  // Whether every particle is in an equality row's cluster: then solve_positions on rows
  // that include the equality rows writes every particle's impulse.
  bool equalities_hold_every_particle(const Particles& particles);
  // Cluster k of the last cluster_rows(rows, ...).
  const Cluster& cluster_at(const std::vector<Constraint>& rows, std::size_t index) const;
  // solve() (the clusters begin..end-1 of one chunk) between the passes' before and after.
  template <class Solve>
  void around_clusters(const std::vector<Constraint>& rows, const ClusterPasses* passes, int chunk,
                       std::size_t begin, std::size_t end, const Solve& solve) const;
  // Adds this step's statistics and virial to every sampler's.
  void finish_step();

  ConstraintSet constraints_;
  ForceEngine engine_;
  double dt_;
  ReflectionOperator reflection_;
  ReflectionEnergy energy_;
  ConstraintStatistics stats_;  // this step's (and setup's) figures, see finish_step()
  std::array<ConstraintStatistics, 2> sampled_;
  double step_virial_ = 0.0;              // sum of r . J over this step's constraint impulses
  std::array<double, 2> virial_sums_{};   // sum over steps of step_virial_ / h, per sampler
  std::vector<Vec3> projected_momenta_;   // project_velocities' momenta: its storage, not values
  std::vector<Vec3> previous_positions_;  // linearisation point of `linearized` constraints
  // max |r - L| / L over the equality rows at the positions of the last project_momenta,
  // when it projected them alone and every cluster by a chain kernel (which measures the
  // lengths there); else -1.
  double projected_deviation_ = -1.0;
  bool setting_up_ = false;  // solves of setup(): failures name the start
  // Performance only: the equality rows' clusters, prepared once; the last clustering.
  EqualityClusters equality_clusters_;
  std::vector<Cluster> found_clusters_;
  // Per chunk of a threaded cluster loop: its chains' scratch space.
  std::vector<RodChainWorkspace> chain_works_;
  // Per chunk: scratch space of the lockstep chain kernels (consecutive chains of equal
  // length solved together, one per vector lane).
  std::vector<RodChainLanes> chain_lanes_;
  // Per cluster of the last cluster loop: its virial terms, its solve's iterations.
  OrderedTerms virial_terms_;
  std::vector<int> cluster_iterations_;
  std::vector<int> equality_iterations_;  // per equality cluster, its last solve's iterations
  // Per equality cluster: its chain's virial from that solve, and whether the chain kernel
  // made it (else nothing to reuse).
  std::vector<double> equality_chain_virial_;
  std::vector<char> equality_chain_solved_;
  PairHessianPieces hessian_blocks_;  // gather_hessian_blocks' (ShadowPairs point into them)
  // gather_hessian_blocks' scratch and results: each reflected cluster's number among them
  // (-1 for the others), its particles' (-1 elsewhere) and their index within it; the mask;
  // the reflected clusters' shadow pairs by number.
  std::vector<std::int32_t> reflected_number_;
  std::vector<std::int32_t> cluster_of_particle_;
  std::vector<std::int32_t> local_index_of_particle_;
  std::vector<char> hessian_mask_;
  ShadowPairs shadow_pairs_;
  // reflect_inequalities': the components of the rows of its calls within a step; per chunk
  // of a call, the rows sharing no particle that it reflects and its clusters of several
  // rows (their lists' storage kept: clusters_used of them are the call's), where the chunks'
  // threads walk the components their seeds, walker and a component's particles; and the rows
  // it left approaching (the next call's seeds, with the rows it adds), marked with the call's
  // number where the chunks' threads walk.
  struct ReflectionChunk {
    std::vector<std::int32_t> lone_rows;
    std::vector<Cluster> clusters;
    std::size_t clusters_used = 0;
    std::vector<std::int32_t> seeds, particles;
    GrowingRowComponents::Walker walker;
  };
  GrowingRowComponents row_components_;
  std::vector<std::int32_t> reflection_seeds_, component_particles_;
  std::vector<OnItsOwnLine<ReflectionChunk>> reflection_chunks_;
  std::vector<OnItsOwnLine<std::vector<std::int32_t>>> unsettled_of_chunk_;
  std::vector<std::uint32_t> seed_mark_;
  std::uint32_t seed_call_ = 0;
  // The reflections' virial terms, and per chunk of reflect_inequalities its counters.
  TermsByRow reflection_terms_;
  std::vector<OnItsOwnLine<ConstraintStatistics>> reflection_stats_;
};

std::vector<Vec3> gather(const std::vector<Vec3>& all, const std::vector<std::int32_t>& which);
void gather(const std::vector<Vec3>& all, const std::vector<std::int32_t>& which,
            std::vector<Vec3>& out);
void scatter(const std::vector<Vec3>& local, const std::vector<std::int32_t>& which,
             std::vector<Vec3>& all);
bool contains(const std::vector<Constraint>& rows, const Constraint& c);
// Per candidate, contains(rows, candidate) into `contained` (1 or 0), by one sort of the rows'
// particle pairs instead of a scan of every row per candidate (thousands of candidates
// against hundreds of active rows in a 32000-sphere fluid). `scratch` is reused.
void mark_contained(const std::vector<Constraint>& rows, const RowStretches& candidates,
                    std::vector<std::pair<std::uint64_t, std::int32_t>>& scratch,
                    std::vector<char>& contained);
// grad g . M^-1 p for a row with unit direction u at its particles.
double normal_velocity(const Constraint& c, const Vec3& u, const std::vector<Vec3>& p,
                       const Particles& P);

}  // namespace deli
