#pragma once

#include <cstdint>
#include <memory>

#include "simulation/degrees_of_freedom.hpp"
#include "system/particles.hpp"

namespace deli {

enum class ThermostatKind { langevin, csvr };

struct ThermostatSettings {
  ThermostatKind kind = ThermostatKind::langevin;
  double temperature = 1.0;
  double damping = 1.0;  // time units: Langevin 1/friction, CSVR the relaxation time
  std::uint64_t seed = 1;
  // The thermostat acts for the steps before this one (equilibration, then NVE); -1: always.
  std::int64_t until_step = -1;
};

// A heat bath acting on the momenta for a span of time, as one half of a splitting around
// the integrator's step (bath for h/2, step, bath for h/2). Its random numbers are drawn
// for (seed, step, which half, atom id), so they are the same whatever the order or the
// thread count of the particles, and a restart continues them from the step alone.
class Thermostat {
 public:
  virtual ~Thermostat() = default;
  // `half`: 0 before the step from `step`, 1 after the step that reached `step`.
  virtual void apply(Particles& particles, std::int64_t step, int half, double duration) = 0;
  // Whether the momenta must afterwards be projected back onto the rods' cotangent space
  // (each particle got its own kick); a global rescaling keeps them there by itself.
  virtual bool needs_projection() const = 0;
};

// Ornstein-Uhlenbeck update of every momentum (the O of BAOAB/OBABO splittings):
// p <- c p + sqrt((1 - c^2) m kT) xi, c = exp(-duration / damping).
class LangevinThermostat final : public Thermostat {
 public:
  explicit LangevinThermostat(const ThermostatSettings& settings) : settings_(settings) {}
  void apply(Particles& particles, std::int64_t step, int half, double duration) override;
  bool needs_projection() const override { return true; }

 private:
  ThermostatSettings settings_;
};

// Bussi, Donadio and Parrinello (J. Chem. Phys. 126, 014101, 2007) stochastic velocity
// rescaling: the kinetic energy follows its canonical distribution for `dof` degrees of
// freedom with relaxation time `damping`, all velocities scaled by one factor.
class CsvrThermostat final : public Thermostat {
 public:
  CsvrThermostat(const ThermostatSettings& settings, double dof) : settings_(settings), dof_(dof) {}
  void apply(Particles& particles, std::int64_t step, int half, double duration) override;
  bool needs_projection() const override { return false; }

 private:
  ThermostatSettings settings_;
  double dof_;
};

std::unique_ptr<Thermostat> make_thermostat(const ThermostatSettings& settings,
                                            const DegreesOfFreedom& dof);

}  // namespace deli
