#pragma once

#include "simulation/thermo.hpp"

namespace deli {

// Something that watches a run: the thermo table, a CSV file, the progress line.
class Observer {
 public:
  virtual ~Observer() = default;
  virtual void on_start(const System&, std::int64_t /*steps*/) {}
  virtual void on_thermo(const ThermoSample&) {}
  // Whether its samples must carry the integrator's shadow energy (ThermoSample::
  // shadow_energy): the CSV and H5MD writers record it; the table on the terminal does not
  // show it. The run finds it only where an observer asks: a pass over every listed pair
  // (LJ 32000 sampled every 100 steps: 2 % of the loop).
  virtual bool wants_shadow_energy() const { return false; }
  virtual void on_step(const System&) {}  // after every step: keep it cheap
  // After every step once its thermo row and frames are out (checkpoints).
  virtual void on_step_complete(const System&) {}
  // Trajectory writers: whether the state after `step` is a frame, and the frame itself
  // with the thermodynamic state at that step (constraint impulses and statistics over the
  // steps since the previous frame) and the force field's forces on each atom.
  virtual bool wants_frame(std::int64_t /*step*/) const { return false; }
  virtual void on_frame(const System&, const ThermoSample&, const std::vector<Vec3>& /*forces*/) {}
  virtual void on_finish(const System&) {}
};

}  // namespace deli
