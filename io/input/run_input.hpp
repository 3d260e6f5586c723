#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "constraints/constraint_set.hpp"
#include "force_field_spec.hpp"
#include "forces/force_field.hpp"
#include "h5md/checkpoint.hpp"
#include "h5md/trajectory_spec.hpp"
#include "integrators/collision_integrator.hpp"
#include "integrators/direct_substitution.hpp"
#include "integrators/gvi.hpp"
#include "integrators/quickmin.hpp"
#include "simulation/degrees_of_freedom.hpp"
#include "system/particle_order.hpp"
#include "thermostats/thermostat.hpp"

namespace deli {

struct DumpOutputSpec {
  std::string file;               // "" = none
  std::string format = "lammps";  // lammps (dump custom) | xyz
  std::int64_t every = 1000;
};

struct ThermoOutputSpec {
  std::int64_t every = 100;
  std::string file;  // "" = no CSV
};

// Everything a `deli run` needs, read from a TOML input and the files it names.
struct RunInput {
  std::string path;
  std::string data_file;  // the LAMMPS data file read, "" for a built system
  System system;
  ForceFieldSpec force_field_spec;
  std::unique_ptr<ForceField> force_field;  // built from force_field_spec
  std::string integrator = "verlet";
  double timestep = 0.005;
  double skin = 0.3;
  std::int64_t steps = 0;
  // [neighbor] sort_every: the particles put in spatial order at the start and every so many
  // steps (system/particle_order.hpp); 0: never.
  std::int64_t sort_every = 1000;
  int threads = 0;  // [run] threads; 0: OpenMP's default (OMP_NUM_THREADS, else all cores)
  // [run] split_small_loops: the per-particle passes split over the threads in chunks of at
  // least 512 items and the rod-cluster loops in chunks of 256 rows (false: 8192 and 1024;
  // core/parallel.hpp).
  bool split_small_loops = true;
  // [run] balance_threads: the chunks of the loops whose numbers do not depend on them moved
  // between steps by the threads' measured speeds (core/chunk_balance.hpp); false: equal.
  bool balance_threads = true;
  ThermoOutputSpec thermo;
  TrajectorySpec trajectory;
  DumpOutputSpec dump;
  struct {
    std::string file;  // "" = none
    std::int64_t every = 10000;
  } checkpoint;
  std::string final_data;     // [output] final_data: the last state as a LAMMPS data file
  std::string log;            // [output] log: a copy of what the run prints
  std::string source_text;    // the input as read, stored with trajectories
  std::string model_text;     // [forcefield] and [constraints] as canonical TOML (checkpoints)
  MinimizeSettings minimize;  // max_steps 0: none
  ConstraintSet constraints;
  GviOptions gvi;              // timestep and skin copied from above
  DirectOptions direct;        // type = "direct"
  CollisionOptions collision;  // type = "collision"
  std::optional<ThermostatSettings> thermostat;
  DegreesOfFreedom degrees_of_freedom;  // counts the rods and what the walls etc. conserve
  // [velocities] temperature: the velocities are drawn when the input is read and scaled
  // to it once the run has made them tangent to the rods (with degrees_of_freedom).
  std::optional<double> start_temperature;
  // What the run should say about its input: where coefficients came from.
  std::vector<std::string> notes;
};

// Reads and validates the input; every error is an InputError naming file:line and key.
RunInput load_run_input(const std::string& path);
// The same from TOML text; `path` names it in messages and anchors relative file names.
RunInput parse_run_input(const std::string& text, const std::string& path);
// Puts the system in `order` with everything built on its indices: the constraints and the
// force field (made anew from its spec).
void reorder_run_input(RunInput& input, const ParticleOrder& order);
// Puts a checkpoint's state into the input that wrote it (read afresh): its particles first
// put in the checkpoint's order (a run that sorts them writes them in the order it has
// reached), then apply_checkpoint.
void restore_run_input(RunInput& input, const Checkpoint& checkpoint, const std::string& path,
                       std::optional<std::uint64_t> fingerprint = std::nullopt);

}  // namespace deli
