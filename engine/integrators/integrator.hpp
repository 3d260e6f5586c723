#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "integrators/force_engine.hpp"

namespace deli {

// Appends to `out` the three numbers a particle from `triples` on (particle i's at
// triples + 3 i) in `order` (order[k]: the particle put k-th).
inline void append_triples_in_order(const double* triples, const std::vector<std::int32_t>& order,
                                    std::vector<double>& out) {
  for (const std::int32_t i : order) {
    const double* x = triples + 3 * static_cast<std::size_t>(i);
    out.insert(out.end(), x, x + 3);
  }
}

// Who samples the integrator's accumulated figures: the thermo output and the trajectory
// frames each get their own tally, since they sample at different intervals.
enum class Sampler { thermo = 0, frame = 1 };

// Advances a system by one timestep. setup() brings forces up to date before the first
// step; after every step, forces() holds those at the new positions, with energies and
// virial when the step was asked to `tally` them.
class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual std::string name() const = 0;
  virtual double timestep() const = 0;
  virtual void setup(System& system) = 0;
  // Continues from a checkpoint: the neighbour list rebuilt from the saved build positions
  // and forces computed, the state itself left untouched (no projection).
  void resume(System& system, const std::vector<Vec3>& build_positions,
              const std::vector<double>& state) {
    restore_state(state, system);
    engine().restore_neighbors(system, build_positions);
    engine().compute(system);
  }
  // What a checkpoint must carry beyond the particles to continue bit for bit.
  virtual std::vector<double> saved_state() const { return {}; }
  // A saved_state() of this integrator with its per-particle parts put in `order`
  // (order[k]: the particle put k-th), for the system so reordered.
  virtual std::vector<double> state_in_order(const std::vector<double>& state,
                                             const std::vector<std::int32_t>& /*order*/) const {
    return state;
  }
  virtual ForceEngine& engine() = 0;
  // Takes back saved_state(); refuses one that is not this integrator's for this system.
  virtual void restore_state(const std::vector<double>& state, const System&) {
    if (!state.empty()) {
      throw InputError("the checkpoint carries state of another integrator than '" + name() +
                       "'; restart with the input that wrote it");
    }
  }
  virtual void step(System& system, bool tally = true) = 0;
  virtual const ForceEngine& forces() const = 0;
  // Named figures accumulated since the sampler's last call (constraint statistics).
  // `keep`: report them without starting a new span, for a sample that is not one of the
  // sampler's regular ones (a run's last step), so that a checkpoint taken there carries
  // what the next regular sample must still count.
  virtual std::vector<std::pair<std::string, double>> take_statistics(Sampler = Sampler::thermo,
                                                                      bool /*keep*/ = false) {
    return {};
  }
  // The constraint impulses' virial, sum of r . J / h per step, averaged over the steps
  // since the sampler's last call: impulses are instantaneous, one step's would be noise.
  virtual double take_constraint_virial(Sampler = Sampler::thermo, bool /*keep*/ = false) {
    return 0.0;
  }
  // Verlet's modified energy H - h^2/24 F.M^-1.F + h^2/12 v.d2V.v (potential forces only),
  // for Verlet-based integrators whose force field has pairwise Hessians.
  virtual std::optional<double> shadow_energy(const System&) const { return std::nullopt; }
  // Makes the velocities tangent to the equality constraints (rods, strings) again after
  // something outside the step changed them (a thermostat); a no-op without constraints.
  virtual void project_velocities(System&) {}
  // The energy a heat bath has put into the system since the run began (nothing: NVE).
  virtual std::optional<double> bath_energy() const { return std::nullopt; }
};

}  // namespace deli
