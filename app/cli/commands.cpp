#include "cli/commands.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "cli/exit_status.hpp"
#include "cli/integrator_factory.hpp"
#include "core/chunk_balance.hpp"
#include "core/cpu_quota.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/thread_team.hpp"
#include "h5md/checkpoint.hpp"
#include "h5md/fingerprint.hpp"
#include "h5md/h5md_info.hpp"
#include "h5md/h5md_writer.hpp"
#include "input/lammps_data.hpp"
#include "input/output_paths.hpp"
#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "integrators/quickmin.hpp"
#include "integrators/reordering_integrator.hpp"
#include "integrators/velocity_verlet.hpp"
#include "simulation/interrupt.hpp"
#include "simulation/run_loop.hpp"
#include "simulation/timing_table.hpp"
#include "solvers/position_problem.hpp"
#include "text/dump_writer.hpp"
#include "text/run_log.hpp"
#include "text/thermo_output.hpp"

namespace deli {

namespace {
namespace fs = std::filesystem;

void minimize_if_asked(RunInput& input, RunLog& out) {
  if (input.minimize.max_steps == 0) return;
  const MinimizeResult r = quickmin(input.system, *input.force_field, input.skin, input.minimize);
  out.print(
      "minimize (quickmin): %lld steps, energy %.10g -> %.10g, largest force component "
      "%.3g (%s)\n",
      static_cast<long long>(r.steps), r.initial_energy, r.final_energy, r.max_force,
      r.converged ? "converged" : "max_steps reached");
}

std::string style_for(const System& system) {
  if (!system.topology.angles.empty() || !system.topology.dihedrals.empty()) return "molecular";
  if (!system.topology.bonds.empty()) return "bond";
  return "atomic";
}

int run_with_output(RunInput& input, const std::string& path, const std::string& restart,
                    const Checkpoint& checkpoint, std::uint64_t fingerprint, RunLog& out);
}  // namespace

void apply_chunk_settings(const RunInput& input) {
  set_chunk_balance(input.balance_threads);
  if (!input.split_small_loops) {
    set_cheap_chunk_minimum(kUnsplitCheapChunk);
    set_cluster_chunk_minimum(kUnsplitClusterChunk);
  }
}

int command_run(const std::vector<std::string>& args) {
  std::string path, restart;
  int threads = 0;
  for (std::size_t k = 0; k < args.size(); ++k) {
    if (args[k] == "--restart") {
      if (k + 1 >= args.size()) throw InputError("deli run: --restart needs a CHECKPOINT file");
      restart = args[++k];
    } else if (args[k] == "--threads") {
      if (k + 1 >= args.size()) throw InputError("deli run: --threads needs a number");
      const std::string& value = args[++k];
      char* end = nullptr;
      const long n = std::strtol(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0' || n < 1 || n > 4096) {
        throw InputError("deli run --threads " + value + ": expected an integer from 1 to 4096");
      }
      threads = static_cast<int>(n);
    } else if (path.empty()) {
      path = args[k];
    } else {
      throw InputError(
          "deli run takes one INPUT file (and --restart CHECKPOINT, --threads N); see deli "
          "--help");
    }
  }
  if (path.empty()) path = DELI_DEFAULT_INPUT;
  RunInput input = load_run_input(path);
  // The command line's count over the input's; neither: OpenMP's default, within a cgroup's
  // CPU quota.
  if (threads == 0) threads = input.threads;
  if (threads > 0) {
    try {
      set_thread_count(threads);
    } catch (const std::invalid_argument& e) {
      throw InputError(std::string("deli run: ") + e.what());
    }
  } else if (const int quota = use_default_thread_count(); quota > 0) {
    input.notes.push_back("note: this process's cgroup has a CPU quota of " +
                          std::to_string(quota) + " CPU" + (quota == 1 ? "" : "s") + ": " +
                          std::to_string(quota) + " thread" + (quota == 1 ? "" : "s") +
                          " by default (--threads N to choose)");
  }
  apply_chunk_settings(input);
  const std::uint64_t fingerprint = system_fingerprint(input.system, input.model_text);
  Checkpoint checkpoint;
  if (!restart.empty()) {
    for (const std::string& output : {input.thermo.file, input.trajectory.file, input.dump.file}) {
      if (!output.empty() && resolved_path(output) == resolved_path(restart)) {
        throw InputError(restart +
                         ": the checkpoint to restart from is also an output of the "
                         "input (thermo, trajectory or dump); name another file");
      }
    }
    checkpoint = read_checkpoint(restart);
    restore_run_input(input, checkpoint, restart, fingerprint);
    if (checkpoint.step >= input.steps) {
      throw InputError(restart + ": the checkpoint is at step " + std::to_string(checkpoint.step) +
                       ", already at the input's " + std::to_string(input.steps) +
                       " steps; raise [run] steps to continue");
    }
  }

  RunLog out;
  if (!input.log.empty()) out.open(input.log, !restart.empty());
  try {
    const int status = run_with_output(input, path, restart, checkpoint, fingerprint, out);
    out.close();
    return status;
  } catch (const std::exception& e) {
    // The log gets the message the terminal gets (from main) before the run ends.
    if (out.file()) std::fprintf(out.file(), "deli: %s\n", e.what());
    throw;
  }
}

namespace {
int run_with_output(RunInput& input, const std::string& path, const std::string& restart,
                    const Checkpoint& checkpoint, std::uint64_t fingerprint, RunLog& out) {
  out.print("deli %s: %s\n", DELI_VERSION, path.c_str());
  const std::size_t dihedrals = input.system.topology.dihedrals.size();
  out.print("%zu atoms, %zu bonds, %zu angles%s; box %g x %g x %g; dt %g, %lld steps\n",
            input.system.particles.size(), input.system.topology.bonds.size(),
            input.system.topology.angles.size(),
            dihedrals == 0 ? "" : (", " + std::to_string(dihedrals) + " dihedrals").c_str(),
            input.system.box.length().x, input.system.box.length().y, input.system.box.length().z,
            input.timestep, static_cast<long long>(input.steps));
  for (const std::string& note : input.notes) out.print("%s\n", note.c_str());
  out.print("%s\n", input.degrees_of_freedom.describe().c_str());
  out.print("%d thread%s%s\n", thread_count(), thread_count() == 1 ? "" : "s",
            !input.split_small_loops && thread_count() > 1 ? " (small loops not split)" : "");
  if (thread_count() > cpus_available()) {
    out.print(
        "note: %d threads on %d CPU%s this process may use: waiting threads sleep or yield "
        "rather than spin; --threads %d is likely faster\n",
        thread_count(), cpus_available(), cpus_available() == 1 ? "" : "s", cpus_available());
  } else if (const std::optional<int> quota = quota_cpus(); quota && thread_count() > *quota) {
    out.print(
        "note: %d threads in a cgroup whose CPU quota is %d CPU%s: the threads wait for the "
        "quota's time; --threads %d is likely faster\n",
        thread_count(), *quota, *quota == 1 ? "" : "s", *quota);
  }
  if (input.thermostat) {
    const ThermostatSettings& t = *input.thermostat;
    out.print("thermostat %s: T %g, damping %g, seed %llu%s\n",
              t.kind == ThermostatKind::langevin ? "langevin" : "csvr", t.temperature, t.damping,
              static_cast<unsigned long long>(t.seed),
              t.until_step < 0 ? ""
                               : (", for steps before " + std::to_string(t.until_step) +
                                  ", then constant energy")
                                     .c_str());
  }

  if (restart.empty()) minimize_if_asked(input, out);
  const std::unique_ptr<Integrator> integrator = make_integrator(input);
  const auto* sorting = dynamic_cast<const ReorderingIntegrator*>(integrator.get());
  // A restart appends to the run's outputs, cut back to what precedes the checkpoint.
  const std::int64_t continue_from = restart.empty() ? -1 : checkpoint.step;
  ThermoTable table(stdout);
  std::vector<Observer*> observers{&table};
  std::unique_ptr<ThermoTable> logged_table;
  if (out.file()) {
    logged_table = std::make_unique<ThermoTable>(out.file());
    observers.push_back(logged_table.get());
  }
  std::unique_ptr<ThermoCsv> csv;
  if (!input.thermo.file.empty()) {
    csv = std::make_unique<ThermoCsv>(input.thermo.file, continue_from, input.thermo.every);
    observers.push_back(csv.get());
  }
  std::unique_ptr<H5mdWriter> trajectory;
  if (!input.trajectory.file.empty()) {
    const char* user = std::getenv("USER");
    std::vector<std::pair<std::int32_t, std::int32_t>> rods;
    for (const Constraint& c : input.constraints.equalities) {
      if (c.kind == ConstraintKind::rod) rods.emplace_back(c.i, c.j);
    }
    trajectory = std::make_unique<H5mdWriter>(
        input.trajectory, input.system, input.source_text, user ? user : "deli user", rods,
        input.constraints.hard_spheres, TrajectoryContinuation{continue_from});
    observers.push_back(trajectory.get());
  }
  std::unique_ptr<DumpWriter> dump;
  if (!input.dump.file.empty()) {
    dump = std::make_unique<DumpWriter>(
        input.dump.file,
        input.dump.format == "xyz" ? DumpWriter::Format::xyz : DumpWriter::Format::lammps,
        input.dump.every, continue_from, input.constraints.hard_spheres);
    observers.push_back(dump.get());
  }
  std::unique_ptr<ProgressLine> progress;
  if (isatty(STDERR_FILENO)) {
    progress = std::make_unique<ProgressLine>(stderr);
    observers.insert(observers.begin(), progress.get());
  }
  std::unique_ptr<CheckpointWriter> checkpoints;
  if (!input.checkpoint.file.empty()) {
    checkpoints = std::make_unique<CheckpointWriter>(input.checkpoint.file, input.checkpoint.every,
                                                     *integrator, fingerprint);
    observers.push_back(checkpoints.get());
  }
  install_interrupt_handlers();
  // A restart continues to the input's step count, from where the checkpoint was written.
  if (!restart.empty()) {
    try {
      integrator->resume(input.system, checkpoint.build_positions, checkpoint.integrator_state);
    } catch (const InputError& e) {
      throw InputError(restart + ": " + e.what());
    }
  }
  RunOptions options;
  options.set_up = restart.empty();
  options.degrees_of_freedom = input.degrees_of_freedom;
  options.start_temperature = input.start_temperature;
  const RunStatistics stats = run(input.system, *integrator, input.steps - input.system.step,
                                  input.thermo.every, observers, options);
  if (stats.interrupted) {
    // The configured checkpoint, else (or if it cannot be written) one in the working
    // directory, as outputs are (the input's directory may be read-only), else one in the
    // temporary directory.
    const std::string name = fs::path(path).filename().string() + ".interrupted.h5";
    std::vector<std::string> places{name, (fs::temp_directory_path() / name).string()};
    if (!input.checkpoint.file.empty()) places.insert(places.begin(), input.checkpoint.file);
    std::string file, failures;
    for (const std::string& place : places) {
      try {
        write_checkpoint(place, input.system, *integrator, fingerprint);
        file = place;
        break;
      } catch (const std::exception& e) {
        failures += std::string("; ") + e.what();
        std::fprintf(stderr, "deli: %s\n", e.what());
      }
    }
    if (file.empty()) {
      throw SimulationError("interrupted after step " + std::to_string(input.system.step) +
                            ", but no checkpoint could be written" + failures);
    }
    out.print(
        "interrupted after step %lld: checkpoint written to %s; continue with\n  deli run "
        "%s --restart %s\n",
        static_cast<long long>(input.system.step), fs::absolute(file).c_str(), path.c_str(),
        fs::absolute(file).c_str());
    return kExitInterrupted;
  }
  // The end of every run is a checkpoint when the run has them, and the final state a data
  // file when asked for.
  if (!input.checkpoint.file.empty() && input.system.step % input.checkpoint.every != 0) {
    write_checkpoint(input.checkpoint.file, input.system, *integrator, fingerprint);
    out.print("final checkpoint at step %lld: %s\n", static_cast<long long>(input.system.step),
              input.checkpoint.file.c_str());
  }
  if (!input.final_data.empty()) {
    write_lammps_data(
        in_input_order(input.system), input.final_data, style_for(input.system),
        "deli " DELI_VERSION " from " + path + " at step " + std::to_string(input.system.step));
    out.print("final state written to %s (LAMMPS data file)\n", input.final_data.c_str());
  }
  out.print(
      "loop time %.3f s for %lld steps of %zu atoms: %.4g atom-steps/s, %lld neighbour "
      "list builds\n",
      stats.loop_seconds, static_cast<long long>(stats.steps), stats.atoms,
      stats.atom_steps_per_second(), static_cast<long long>(stats.neighbor_builds));
  if (const long long spells = crowded_spells(); spells > 0) {
    out.print(
        "note: other processes' threads held this run's CPUs (%lld time%s); its threads then "
        "waited without spinning, a second each time (where runs share the cores, one thread "
        "a run is faster: --threads 1)\n",
        spells, spells == 1 ? "" : "s");
  }
  if (sorting) {
    out.print("particles sorted in space %lld times (every %lld steps)\n",
              static_cast<long long>(sorting->sorts()), static_cast<long long>(input.sort_every));
  }
  if (const std::vector<double> shares = chunk_shares(); !shares.empty()) {
    std::string listed;
    for (const double share : shares) {
      char text[32];
      std::snprintf(text, sizeof text, " %.1f %%", 100.0 * share);
      listed += text;
    }
    out.print(
        "threads' shares of the balanced loops at the end:%s (moved %lld times by their "
        "speeds; [run] balance_threads)\n",
        listed.c_str(), chunk_balance_moves());
  }
  out.print("%s", timing_table(stats).c_str());
  return 0;
}
}  // namespace

int command_info(const std::vector<std::string>& args) {
  if (args.size() != 1) throw InputError("usage: deli info FILE (an H5MD trajectory)");
  std::fputs(describe_h5md(args[0]).c_str(), stdout);
  return 0;
}

int command_write_data(const std::vector<std::string>& args) {
  if (args.size() != 2) throw InputError("usage: deli write-data INPUT FILE");
  RunInput input = load_run_input(args[0]);
  for (const std::string& source : {args[0], input.data_file}) {
    if (!source.empty() && resolved_path(source) == resolved_path(args[1])) {
      throw InputError(args[1] + ": is the input's own " +
                       (source == args[0] ? "input file" : "data file") +
                       "; writing it would destroy it: name another FILE");
    }
  }
  RunLog out;
  minimize_if_asked(input, out);
  write_lammps_data(input.system, args[1], style_for(input.system),
                    "deli " DELI_VERSION " from " + args[0]);
  std::printf("wrote %zu atoms to %s\n", input.system.particles.size(), args[1].c_str());
  return 0;
}

int command_solve_problem(const std::vector<std::string>& args) {
  const char* usage = "usage: deli solve-problem FILE [--newton N]";
  if (args.size() != 1 && args.size() != 3) throw InputError(usage);
  int newton = 0;
  if (args.size() == 3) {
    if (args[1] != "--newton") throw InputError(std::string(usage) + ": unknown " + args[1]);
    char* end = nullptr;
    const long value = std::strtol(args[2].c_str(), &end, 10);
    if (args[2].empty() || *end != '\0' || value < 1 || value > 1000000) {
      throw InputError("--newton " + args[2] + ": expected an integer from 1 to 1000000");
    }
    newton = static_cast<int>(value);
  }
  const PositionProblem problem = read_position_problem(args[0]);
  const PositionUpdate solved = solve_position_problem(problem, newton);
  std::fputs(describe_position_solve(problem, solved).c_str(), stdout);
  return solved.status.converged ? kExitSuccess : kExitSimulationStopped;
}

}  // namespace deli
