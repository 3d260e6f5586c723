#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/exit_status.hpp"
#include "core/error.hpp"

namespace {

constexpr const char* kUsage =
    "usage: deli <command> [arguments]\n"
    "\n"
    "commands:\n"
    "  run [INPUT] [--restart CHECKPOINT] [--threads N]\n"
    "                            run a simulation (no INPUT: the default input,\n"
    "                            " DELI_DEFAULT_INPUT
    ")\n"
    "  validate INPUT [--engine openmm|lammps|all] [--platform reference|cpu] [--steps N]\n"
    "                            compare energies, forces, virial and an N-step (100)\n"
    "                            NVE trajectory with OpenMM and LAMMPS in-process\n"
    "  info FILE                 summarise an H5MD trajectory\n"
    "  write-data INPUT FILE     write the system INPUT builds as a LAMMPS data file\n"
    "  solve-problem FILE [--newton N]\n"
    "                            solve again a failed constraint solve a run dumped\n"
    "                            (deli-failed-solve-stepN.txt)\n"
    "\n"
    "options:\n"
    "  -h, --help                this help\n"
    "  --version                 the version\n";

// `deli COMMAND --help`.
constexpr const char* kRunUsage =
    "usage: deli run [INPUT] [--restart CHECKPOINT] [--threads N]\n"
    "\n"
    "Runs the simulation INPUT (a TOML file; none: the default input,\n" DELI_DEFAULT_INPUT
    ").\n"
    "Prints the thermo table; writes the outputs of its [output] table. SIGINT or SIGTERM\n"
    "stop after the current step with a checkpoint (exit status 130).\n"
    "\n"
    "  --restart CHECKPOINT      continue from a checkpoint written by a run of this INPUT,\n"
    "                            to its [run] steps, appending to its outputs\n"
    "  --threads N               run on N threads (over [run] threads; neither: the\n"
    "                            OMP_NUM_THREADS environment variable, else all cores,\n"
    "                            within a cgroup's CPU quota).\n"
    "                            The same input on as many threads gives the same\n"
    "                            results bit for bit\n";
constexpr const char* kValidateUsage =
    "usage: deli validate INPUT [--engine openmm|lammps|all] [--platform reference|cpu]\n"
    "                     [--steps N]\n"
    "\n"
    "Builds INPUT's model in deli, OpenMM and LAMMPS (in this process) and compares the\n"
    "energy of every term, every force component, the virial and the positions after an\n"
    "N-step (default 100) NVE trajectory. Exit status 0 when all agree within tolerance.\n";
constexpr const char* kInfoUsage =
    "usage: deli info FILE\n"
    "\n"
    "Summarises an H5MD trajectory (particles, frames, observables, temperature and its\n"
    "degrees of freedom) or a deli checkpoint.\n";
constexpr const char* kSolveProblemUsage =
    "usage: deli solve-problem FILE [--newton N]\n"
    "\n"
    "Reads a position-update problem a failed run wrote (deli-failed-solve-stepN.txt) and\n"
    "solves it again as the run did (with N Newton iterations at most, if given): prints\n"
    "whether it converges, the residual, and each row's gap and impulse. Exit status 0 when\n"
    "it converges, 3 when it does not.\n";
constexpr const char* kWriteDataUsage =
    "usage: deli write-data INPUT FILE\n"
    "\n"
    "Writes the system INPUT builds (after its [minimize], if any) as a LAMMPS data file.\n";

bool asks_for_help(const std::vector<std::string>& args) {
  for (const std::string& a : args) {
    if (a == "-h" || a == "--help") return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "-h" || args[0] == "--help" || args[0] == "help") {
      std::fputs(kUsage, stdout);
      return args.empty() ? deli::kExitUsage : deli::kExitSuccess;
    }
    if (args[0] == "--version") {
      std::printf("deli %s\n", DELI_VERSION);
      return 0;
    }
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (asks_for_help(rest)) {
      const char* usage = args[0] == "run"             ? kRunUsage
                          : args[0] == "validate"      ? kValidateUsage
                          : args[0] == "info"          ? kInfoUsage
                          : args[0] == "write-data"    ? kWriteDataUsage
                          : args[0] == "solve-problem" ? kSolveProblemUsage
                                                       : nullptr;
      if (usage) {
        std::fputs(usage, stdout);
        return 0;
      }
    }
    if (args[0] == "run") return deli::command_run(rest);
    if (args[0] == "write-data") return deli::command_write_data(rest);
    if (args[0] == "validate") return deli::command_validate(rest);
    if (args[0] == "info") return deli::command_info(rest);
    if (args[0] == "solve-problem") return deli::command_solve_problem(rest);
    std::fprintf(stderr, "deli: unknown command '%s'; run 'deli --help' for the commands\n",
                 args[0].c_str());
    return deli::kExitUsage;
  } catch (const deli::InputError& e) {
    std::fprintf(stderr, "deli: input error: %s\n", e.what());
    return deli::kExitInputError;
  } catch (const deli::SimulationError& e) {
    std::fprintf(stderr, "deli: simulation stopped: %s\n", e.what());
    return deli::kExitSimulationStopped;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "deli: out of memory: the system (or an output buffer) does not fit in this "
                 "machine's memory; check the number of atoms and the box\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "deli: error: %s\n", e.what());
  }
  return deli::kExitInputError;
}
