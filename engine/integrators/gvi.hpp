#pragma once

#include <array>
#include <limits>

#include "constraints/clusters.hpp"
#include "constraints/constraint_set.hpp"
#include "integrators/integrator.hpp"
#include "integrators/reflection.hpp"

namespace deli {

// Counters over a span of steps (one step, or the steps between two samples).
struct GviStatistics {
  std::int64_t steps = 0;
  std::int64_t active = 0;            // rows in the extended active sets
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

  void add(const GviStatistics& later);
  // As numbers for a checkpoint (counts are exact in a double up to 2^53).
  void save(std::vector<double>& out) const;
  static constexpr std::size_t saved_size = 15;
  static GviStatistics load(const double* in);
};

// The generalized variational integrator (Kaufman & Pai, Algorithm 1) with the Verlet
// discrete Lagrangian: forward predictor, extended active set, energy-preserving
// reflection, smooth set, position update (a complementarity problem per cluster),
// momentum update. With rods only it is RATTLE; with no constraints, velocity Verlet.
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
};

class Gvi final : public Integrator {
 public:
  Gvi(const ForceField& force_field, ConstraintSet constraints, const GviOptions& options,
      const Particles& particles);

  std::string name() const override { return reflections_ ? "gvi" : "dsi"; }
  double timestep() const override { return dt_; }
  // Puts the state on the constraint manifold (positions, then momenta) and computes forces.
  void setup(System& system) override;
  ForceEngine& engine() override { return engine_; }
  void step(System& system, bool tally = true) override;
  const ForceEngine& forces() const override { return engine_; }
  std::vector<std::pair<std::string, double>> take_statistics(
      Sampler sampler = Sampler::thermo) override;
  double take_constraint_virial(Sampler sampler = Sampler::thermo) override;
  std::vector<double> saved_state() const override;
  void restore_state(const std::vector<double>& state, const System& system) override;
  std::optional<double> shadow_energy(const System& system) const override {
    if (lagrangian_ != Lagrangian::verlet) return std::nullopt;
    return engine_.verlet_shadow_energy(system, dt_);
  }

  const ConstraintSet& constraints() const { return constraints_; }

 private:
  double solve_positions(System& system, const std::vector<Constraint>& rows,
                         const std::vector<bool>& equality, const std::vector<Vec3>& q,
                         const std::vector<Vec3>& delta, std::vector<Vec3>& impulse);
  ShadowOperator shadow_operator(const System& system, const Cluster& cluster,
                                 const std::vector<Vec3>& p) const;
  void reflect_clusters(System& system, const std::vector<Constraint>& rows,
                        std::size_t first_inequality, const std::vector<Vec3>& x,
                        std::vector<Vec3>& p);
  double project_momenta(System& system, const std::vector<Constraint>& rows,
                         const std::vector<Vec3>& x, std::vector<Vec3>& p);
  void record_geometry(const System& system, const std::vector<Constraint>& candidates, bool full);
  [[noreturn]] void midpoint_failure(const System& system, double change) const;
  void restore_energy(System& system, const std::vector<Constraint>& landed, double target,
                      std::vector<Vec3>& p);

  ConstraintSet constraints_;
  ForceEngine engine_;
  double dt_;
  ReflectionOperator reflection_;
  ReflectionEnergy energy_;
  Feasibility feasibility_;
  Lagrangian lagrangian_;
  bool reflections_;
  bool constrained_predictor_;
  GviStatistics stats_;  // this step's (and setup's) figures, added to each sampler's at its end
  std::array<GviStatistics, 2> sampled_;
  double step_virial_ = 0.0;              // sum of r . J over this step's constraint impulses
  std::array<double, 2> virial_sums_{};   // sum over steps of step_virial_ / h, per sampler
  std::vector<Vec3> previous_positions_;  // linearisation point of `linearized` constraints
};

}  // namespace deli
