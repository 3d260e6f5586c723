#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "constraints/nearby_rows.hpp"
#include "integrators/constrained_integrator.hpp"
#include "integrators/gvi_workspace.hpp"
#include "integrators/impact_time_drift.hpp"
#include "integrators/shadow_correction.hpp"

namespace deli {

// The generalized variational integrator (Kaufman & Pai, Algorithm 1) with the Verlet
// discrete Lagrangian: forward predictor, extended active set, energy-preserving
// reflection, smooth set, position update (a complementarity problem per cluster),
// momentum update. With rods only it is RATTLE; with no constraints, velocity Verlet's
// algorithm (the same numbers until the first neighbour-list rebuild, after which the pair
// sums round differently: GVI builds its list from wrapped positions; see
// tests/properties/integrator_variants_test.cpp).
// Choices the paper leaves open are documented in the README ("GVI").
//
// Feasibility guard (the paper lets a step end overlapped, e.g. a slow particle pulled into
// a wall whose predicted overlap it does not approach fast enough to reflect): rows that
// would end the step overlapped join the position update's complementarity set, which
// lands them at contact; then `reflect` reflects the momenta still approaching them at the
// end of the step (elastic), `inelastic` projects that approach away, `none` keeps the
// literal algorithm (overlaps are only counted).
// `restore` is `reflect` followed by an impulse along the landed rows' normals that brings
// the energy H back to its value at the start of the step (the landing moved the particle
// and changed its potential energy); where the normal motion cannot supply the difference
// the normal velocity is zeroed and the event counted as a deficit.
enum class Feasibility { restore, reflect, inelastic, none };
enum class Lagrangian { verlet, midpoint };
// How a hard-sphere or wall contact is resolved. `paper`: Algorithm 1 (reflection at the
// start of the step whose prediction overlaps, then the position update). `impact_time`:
// half kick, the exact hard-sphere and wall flow over h (straight flight, elastic
// reflection at the instant of contact; impact_time_drift.hpp), half kick; Verlet only; with
// rods or strings the RATTLE drift split at each contact (README, "Contact treatment").
enum class ContactTreatment { paper, impact_time };

struct GviOptions {
  Lagrangian lagrangian = Lagrangian::verlet;
  // false: the Discrete-Smooth Integrator (no reflections; every row of the extended
  // active set enters the position update's complementarity problem).
  bool reflections = true;
  // Predict with the equality rows solved (else the unconstrained step, as the paper).
  bool constrained_predictor = false;
  double timestep = 0.005;
  double skin = 0.3;
  ReflectionOperator reflection = ReflectionOperator::generalized;
  ReflectionEnergy energy = ReflectionEnergy::hamiltonian;
  Feasibility feasibility = Feasibility::restore;
  ContactTreatment contact = ContactTreatment::paper;
  // impact_time (hard spheres, walls, rods; not strings): with K > 0 the restoration on a
  // contact step also gives back the modified energy's rest beyond h^2, read from K virtual
  // Verlet (with rods RATTLE) steps either side of the step (shadow_remainder.hpp); 0: S alone.
  int shadow_remainder_steps = 0;
};

class Gvi final : public ConstrainedIntegrator {
 public:
  Gvi(const ForceField& force_field, ConstraintSet constraints, const GviOptions& options,
      const Particles& particles);

  std::string name() const override { return reflections_ ? "gvi" : "dsi"; }
  void step(System& system, bool tally = true) override;
  std::optional<double> shadow_energy(const System& system) const override {
    if (lagrangian_ != Lagrangian::verlet) return std::nullopt;
    if (!constraints_.equalities.empty()) {
      return verlet_shadow_energy_on_rods(engine_, system, dt_, constraints_.equalities);
    }
    return engine_.verlet_shadow_energy(system, dt_);
  }

 private:
  // The phases of one step, in order, over the workspace ws_ (each timed on its own).
  // Momenta, start positions and the first prediction; rebuilds the neighbour list first
  // if the prediction leaves it.
  void start_step(System& system);
  // Extended active set, reflecting the momenta and predicting again until it stops growing.
  void find_active_set(System& system);
  // Rows active at q and tangent to the reflected momenta.
  void find_smooth_set(const System& system);
  // Position update (complementarity per cluster) and the feasibility guard; leaves the end
  // positions in ws_.x.
  void update_positions(System& system);
  // Moves to x, computes the new forces, kicks, projects the momenta, restores the energy of
  // landings.
  void update_momenta(System& system, bool tally);
  // Overlap and rod checks for the statistics.
  void check_constraints(const System& system, bool tally);
  // The whole step with contact = impact_time (gvi_impact_time.cpp), and its input checks.
  void refuse_impact_times_unless_supported() const;
  void step_with_impact_times(System& system, bool tally);
  void step_with_impact_times_and_rods(System& system, bool tally);  // gvi_impact_time_rods.cpp
  void restore_shadow_remainder(System& system, const std::vector<Constraint>& touched,
                                double target, double shadow_target, std::vector<Vec3>& p);
  // What an impact-time drift reached: its longest particle path, its end positions and the
  // contact configurations it passed through.
  struct DriftSpan {
    double longest;
    const std::vector<Vec3>* end;
    const std::vector<std::vector<Vec3>>* vertices;
  };
  // Runs `drift_once` until the candidate rows and the neighbour list cover every position it
  // passed through: rebuilds the list (the step restarts from the wrapped positions) or
  // widens the rows' reach and runs it again; three tries, then an error naming the step.
  void drift_with_covering_rows(System& system, bool pairs_matter,
                                const std::function<DriftSpan()>& drift_once);

  // The unconstrained step's displacement from the current positions for momenta `momenta`;
  // then after(begin, end) for each chunk of particles, the chunks as the particle passes split
  // (Verlet: in the displacement's own pass, on the thread that made the chunk's).
  void free_displacement(System& system, const std::vector<Vec3>& momenta, std::vector<Vec3>& d,
                         const std::function<void(std::size_t, std::size_t)>& after);
  // The predictor's end positions into `x`: the free step, or (`constrained`) that step with
  // the equality rows solved. `again`: a later prediction of the same step (same positions
  // and forces, momenta changed by reflections), which re-solves only the chains it must.
  void predict(System& system, const std::vector<Vec3>& momenta, std::vector<Vec3>& x,
               bool constrained, bool again = false);
  // The candidate rows for a step from q to x (refreshed when x outgrows their reach).
  // `largest2_bound`, when given, is at least max |x - q|^2 (the exact value if `exact`):
  // what decides a refresh without a pass over the particles when it shows none is due.
  // `moved`, when given, holds the only particles whose x changed since the last call.
  // `then`, when given, is handed to the collection by particle reach, if one is made
  // (NearbyRows::collect); `*then_ran` tells whether it ran.
  const RowStretches& candidates_for(const System& system, const std::vector<Vec3>& x,
                                     double largest2_bound = -1.0, bool exact = false,
                                     const std::vector<std::int32_t>* moved = nullptr,
                                     const NearbyRows::StretchPass* then = nullptr,
                                     bool* then_ran = nullptr);
  // This step's end positions (ws_.x, or the positions once the momentum update swapped x into
  // them), and whether v is that vector.
  const std::vector<Vec3>& x_now(const System& system) const;
  bool is_x(const System& system, const std::vector<Vec3>& v) const;
  // Whether the system has inequality rows at all (hard spheres or walls).
  bool has_inequalities() const;
  // Candidates by a reach per particle (the paper's contact treatment without linearised
  // rows) instead of one reach from the step's largest displacement.
  bool particle_reaches() const;
  bool reaches_cover(const std::vector<Vec3>& x, const std::vector<std::int32_t>* moved) const;
  // Whether `then` ran (NearbyRows::collect).
  bool collect_by_particle_reach(const System& system, const std::vector<Vec3>& x,
                                 const NearbyRows::StretchPass* then = nullptr);
  static constexpr double kReachFloor = 0.5;
  // Without equality rows and with Verlet: the rows reflected (those before `first_new_row`
  // the last round's, see reflect_clusters), and the free prediction made again for the
  // reflected particles alone.
  // Given `next_test`, run in the reflections' job where they run in one (reflect_clusters'
  // `then` over `test_count` rows), once every prediction is made, unless a changed one left
  // its particle's reach; `*tested` tells whether it ran so.
  // With `further` as well, the active set's next rounds in the same job (reflect_clusters'),
  // while the test ran and further->follows(): further->start() then joins a round's rows.
  double reflect_and_predict(System& system, const std::vector<Constraint>& rows,
                             std::size_t first_new_row, const ChunkPass* next_test = nullptr,
                             std::size_t test_count = 0, bool* tested = nullptr,
                             const FurtherRounds* further = nullptr);
  // One solve of the position update for the rows held, with its midpoint fixed point.
  // Returns true where it left the half kick to displaced() (Verlet, no row held: nothing
  // reads it before the end positions).
  bool solve_held_positions(System& system);
  const std::vector<Constraint>& equalities_and(const std::vector<Constraint>& others);
  // Whether the step's per-particle passes go with the cluster solves: on several threads,
  // Verlet, every particle in a cluster of rods (strings), no contact rows and the free
  // predictor (a melt of rigid chains).
  bool steps_by_cluster(const Particles& particles);
  // solve_held_positions and displaced() with the half kick and free step of a chunk's
  // clusters made before their solves and their end positions after (the same numbers).
  void held_positions_by_cluster(System& system);
  // End positions q + h M^-1 (half + impulse) into ws_.x, and max |x - q|^2 into
  // ws_.x_largest2; with `kick`, the half kick made first in the same pass, and where no force
  // acts the momentum update's velocities after it (ws_.velocities_made). Given `then`,
  // then(c, begin, end) for the `chunks` chunks of [0, then_count) in the same job, once
  // every end position is made, each on the thread of chunk c of the end positions (given
  // only where those are `chunks` chunks too).
  void displaced(Particles& particles, bool kick = false, const ChunkPass* then = nullptr,
                 std::size_t then_count = 0);
  double start_energy(System& system);
  // Verlet's shadow energy at the step's start, from its H `start` (none where a force term
  // has no pairwise Hessian).
  std::optional<double> start_shadow_energy(System& system, double start);
  // An impulse along the landed rows' normals that brings H back to `target`, or, given
  // `shadow_target`, Verlet's shadow energy to it (H where the shadow energy is unavailable).
  // With impact_time, where the energy to take away exceeds what the normal motion holds, an
  // impulse along the motion relative to the rigid motion (contact_group.hpp) of the landed
  // rows' particles and their rod clusters, else of all particles; a deficit where none
  // reaches the target.
  void restore_energy(System& system, const std::vector<Constraint>& landed, double target,
                      std::vector<Vec3>& p, std::optional<double> shadow_target = std::nullopt);

  GviWorkspace ws_;
  NearbyRows nearby_rows_;  // candidate rows from a short list kept between steps

  Feasibility feasibility_;
  Lagrangian lagrangian_;
  bool reflections_;
  bool constrained_predictor_;
  ContactTreatment contact_;
  int shadow_remainder_steps_;
  ImpactTimeDrift drift_;
};

}  // namespace deli
