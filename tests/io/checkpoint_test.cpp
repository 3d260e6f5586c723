// A run continued from a checkpoint is the uninterrupted run, bit for bit; damaged
// checkpoints are refused with their name.
#include "h5md/checkpoint.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cli/integrator_factory.hpp"
#include "core/error.hpp"
#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "integrators/velocity_verlet.hpp"
#include "simulation/run_loop.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"
#include "support/short_runs.hpp"

namespace deli {
namespace {

std::unique_ptr<Integrator> integrator_for(RunInput& input) {
  return make_integrator(input);
}

void expect_restart_identical(const std::string& input_path, int first, int second) {
  // ctest runs the cases in parallel: a file of this case's own.
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(test->test_suite_name()) + "_" + test->name();
  std::replace(name.begin(), name.end(), '/', '_');  // parameterised names hold '/'
  const std::string file = deli::testing::process_temp_dir() + "/restart_" + name + "_" +
                           std::to_string(getpid()) + ".h5";
  RunInput straight = load_run_input(input_path);
  auto a = integrator_for(straight);
  run(straight.system, *a, first + second, 0, {});

  RunInput interrupted = load_run_input(input_path);
  auto b = integrator_for(interrupted);
  run(interrupted.system, *b, first, 0, {});
  write_checkpoint(file, interrupted.system, *b);

  RunInput resumed = load_run_input(input_path);
  const Checkpoint checkpoint = read_checkpoint(file);
  restore_run_input(resumed, checkpoint, file);
  auto c = integrator_for(resumed);
  c->resume(resumed.system, checkpoint.build_positions, checkpoint.integrator_state);
  run(resumed.system, *c, second, 0, {}, false);

  ASSERT_EQ(resumed.system.step, straight.system.step);
  ASSERT_EQ(a->bath_energy().has_value(), c->bath_energy().has_value());
  if (a->bath_energy()) ASSERT_EQ(*a->bath_energy(), *c->bath_energy());
  const Particles& x = straight.system.particles;
  const Particles& y = resumed.system.particles;
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(x.position[i][k], y.position[i][k]) << "atom " << x.id[i];
      ASSERT_EQ(x.velocity[i][k], y.velocity[i][k]) << "atom " << x.id[i];
    }
  }
}

TEST(Checkpoint, VerletRestartIsBitwiseIdentical) {
  expect_restart_identical(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml", 75, 75);
}

TEST(Checkpoint, GviRestartIsBitwiseIdentical) {
  expect_restart_identical(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/rigid_slit.toml", 40,
                           40);
}

// The baselines carry state of their own between steps (the direct methods' previous
// step and Newmark's accelerations, the collision integrator's statistics): a restart on
// either side of the first bounce (the ball meets the floor near step 45) continues bit for
// bit, whether the integrator is in contact at the checkpoint or not.
class BaselineRestart : public ::testing::TestWithParam<const char*> {};

TEST_P(BaselineRestart, IsBitwiseIdentical) {
  const std::string input =
      std::string(DELI_SOURCE_DIR) + "/inputs/paper/baselines/" + GetParam() + ".toml";
  for (const int first : {30, 45, 46}) {
    SCOPED_TRACE("checkpoint at step " + std::to_string(first));
    expect_restart_identical(input, first, 150);
  }
}

INSTANTIATE_TEST_SUITE_P(ParticleDrop, BaselineRestart,
                         ::testing::Values("particle_drop_direct_midpoint",
                                           "particle_drop_direct_endpoint", "particle_drop_newmark",
                                           "particle_drop_kane_imex", "particle_drop_collision",
                                           "nonlinear_oscillator_collision"),
                         [](const auto& info) { return std::string(info.param); });

// A thermostat's random numbers are a function of (seed, step, atom): the checkpoint
// carries the seed and the bath's energy, the step gives the rest.
std::string thermostatted_input(const std::string& integrator, const std::string& thermostat) {
  const std::string path = deli::testing::process_temp_dir() + "/thermostatted_" + thermostat +
                           "_" + std::to_string(getpid()) + ".toml";
  std::ofstream(path)
      << "[system]\n[system.chains]\ncount = 20\nlength = 5\ndensity = 0.6\nbond_length = 1.0\n"
         "min_distance = 0.95\nseed = 4\n[velocities]\ntemperature = 1.0\nseed = 3\n"
         "[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n[forcefield.pair]\nstyle = \"wca\"\n"
         "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
      << (integrator == "gvi"
              ? "[constraints]\nbonds = \"rigid\"\nhard_spheres = { diameter = 0.9 }\n"
              : "[forcefield.bond]\nstyle = \"harmonic\"\n"
                "coeffs = [{ type = 1, k = 100.0, r0 = 1.0 }]\n")
      << "[integrator]\ntype = \"" << integrator << "\"\ntimestep = 0.004\n[thermostat]\ntype = \""
      << thermostat << "\"\ntemperature = 1.2\ndamping = 0.5\nseed = 99\n[run]\nsteps = 0\n";
  return path;
}

TEST(Checkpoint, LangevinGviRestartIsBitwiseIdentical) {
  expect_restart_identical(thermostatted_input("gvi", "langevin"), 37, 60);
}

TEST(Checkpoint, CsvrVerletRestartIsBitwiseIdentical) {
  expect_restart_identical(thermostatted_input("verlet", "csvr"), 37, 60);
}

TEST(Checkpoint, CheckpointWithoutThermostatIsRefusedByThermostattedInput) {
  const std::string file =
      deli::testing::process_temp_dir() + "/nve_" + std::to_string(getpid()) + ".h5";
  RunInput nve = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  auto a = integrator_for(nve);
  run(nve.system, *a, 5, 0, {});
  write_checkpoint(file, nve.system, *a);
  RunInput nvt = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  nvt.thermostat = ThermostatSettings{};
  auto b = make_integrator(nvt);
  EXPECT_THROW(b->restore_state(read_checkpoint(file).integrator_state, nvt.system), InputError);
}

// Linearised constraints are linearised about the previous step's positions: integrator
// state the checkpoint must carry. The spheres touch every fifth step (4, 9, ..., 99): the
// restart at 98 meets a contact on its first step, where that point matters.
TEST(Checkpoint, LinearizedConstraintRestartIsBitwiseIdentical) {
  expect_restart_identical(
      std::string(DELI_SOURCE_DIR) + "/inputs/paper/nonlinear_oscillator_linearized.toml", 98, 300);
}

TEST(Checkpoint, DamagedCheckpointIsRefused) {
  const std::string dir =
      deli::testing::process_temp_dir() + "/damaged_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  write_checkpoint(dir + "/good.h5", input.system, input.system.particles.position);
  // Truncated to half its size.
  std::ifstream in(dir + "/good.h5", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  std::ofstream(dir + "/cut.h5", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  for (const std::string& name : {std::string("/cut.h5"), std::string("/none.h5")}) {
    try {
      read_checkpoint(dir + name);
      FAIL() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(dir + name), std::string::npos) << e.what();
    }
  }
  // A checkpoint of another system.
  RunInput other = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/paper/pogo_stick.toml");
  EXPECT_THROW(apply_checkpoint(read_checkpoint(dir + "/good.h5"), other.system, "good.h5"),
               InputError);
}

bool same_checkpoint(const Checkpoint& a, const Checkpoint& b) {
  auto bits = [](const auto& x, const auto& y) {
    return x.size() == y.size() &&
           (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0);
  };
  return a.step == b.step && std::memcmp(&a.time, &b.time, sizeof a.time) == 0 &&
         a.fingerprint == b.fingerprint && bits(a.id, b.id) && bits(a.position, b.position) &&
         bits(a.velocity, b.velocity) && bits(a.image, b.image) &&
         bits(a.build_positions, b.build_positions) && bits(a.integrator_state, b.integrator_state);
}

// Every single byte of a checkpoint flipped in turn (all bits inverted): each damaged file is
// either refused (checksums, sizes, HDF5's own structure) or, where the byte is one HDF5
// never reads (padding, free space), read back exactly. Before the checksums, 57 of 200
// flips restarted with other values (issue 14).
TEST(Checkpoint, EverySingleByteFlipIsRefusedOrHarmless) {
  // A folder of its own: ctest runs other cases in parallel.
  const std::string dir =
      deli::testing::process_temp_dir() + "/byte_flips_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/paper/pogo_stick.toml");
  auto integrator = make_integrator(input);
  run(input.system, *integrator, 37, 0, {});
  write_checkpoint(dir + "/flip.h5", input.system, *integrator, 12345);
  const Checkpoint original = read_checkpoint(dir + "/flip.h5");
  std::ifstream in(dir + "/flip.h5", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GT(bytes.size(), 1000u);
  // Under the sanitizers (each read about 10 times slower) every fifth byte: 5 is coprime to
  // 2, 4 and 8, so the flips still fall at every offset within HDF5's integers, addresses
  // and doubles; the plain pass flips every byte.
  const std::size_t stride = deli::testing::short_runs() ? 5 : 1;
  std::size_t refused = 0, harmless = 0;
  for (std::size_t k = 0; k < bytes.size(); k += stride) {
    std::string flipped = bytes;
    flipped[k] = static_cast<char>(~flipped[k]);
    std::ofstream(dir + "/flipped.h5", std::ios::binary | std::ios::trunc) << flipped;
    try {
      const Checkpoint c = read_checkpoint(dir + "/flipped.h5");
      ASSERT_TRUE(same_checkpoint(original, c)) << "byte " << k << " changed the checkpoint";
      ++harmless;
    } catch (const InputError& e) {
      ASSERT_NE(std::string(e.what()).find(dir + "/flipped.h5"), std::string::npos) << e.what();
      ++refused;
    }
  }
  std::printf("%zu bytes: %zu flips refused, %zu harmless\n", bytes.size(), refused, harmless);
  EXPECT_GT(refused, 0u);
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// Shell text that waits until the run logging to `log` has printed its step-0 thermo row,
// which comes after its interrupt handlers are installed (two minutes at most): a fixed
// sleep sent the signal too early when start-up was slow (a sanitizer build under load), and
// before the handlers a background job ignores SIGINT and dies of SIGTERM.
std::string wait_for_first_row(const std::string& log) {
  return "i=0; until grep -qs \"^ *0 \" " + log +
         " || [ $i -ge 1200 ]; do sleep 0.1; i=$((i+1)); done; ";
}

// The melt run for a very long time, for the signal tests; `steps` makes its restart input.
std::string long_melt(const std::string& dir, const std::string& name, long long steps) {
  const std::string input = dir + "/" + name + ".toml";
  std::ofstream(input) << "[system]\ndata = \"" DELI_SOURCE_DIR
                          "/inputs/lj_chains/melt.data\"\n"
                          "[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n"
                          "[forcefield.pair]\nstyle = \"wca\"\n"
                          "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
                          "[forcefield.bond]\nstyle = \"fene\"\n"
                          "coeffs = [{ type = 1, k = 30.0, r0 = 1.5, epsilon = 1.0, sigma = 1.0 "
                          "}]\n"
                          "[integrator]\ntimestep = 0.005\n[run]\nsteps = "
                       << steps << "\n[output]\nthermo = { every = 1000 }\ncheckpoint = { file = \""
                       << dir << "/stop.h5\", every = 1000000 }\n";
  return input;
}

// SIGINT or SIGTERM mid-run: the step finishes, a checkpoint is written, the exit status is
// 130, and `deli run --restart` continues from the checkpoint to the end.
TEST(Checkpoint, SigintAndSigtermLeaveACheckpointThatRestarts) {
  for (const std::string signal : {"INT", "TERM"}) {
    const std::string dir =
        deli::testing::process_temp_dir() + "/signal_" + signal + "_" + std::to_string(getpid());
    std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
    const std::string input = long_melt(dir, "long", 100000000);
    const std::string command = "sh -c '" + std::string(DELI_BINARY) + " run " + input + " > " +
                                dir + "/stop.log 2>&1 & pid=$!; " +
                                wait_for_first_row(dir + "/stop.log") + "kill -" + signal +
                                " $pid; wait $pid; echo $?'";
    EXPECT_EQ(testing::run_shell(command).output, "130\n") << "SIG" << signal;
    const Checkpoint c = read_checkpoint(dir + "/stop.h5");
    EXPECT_GT(c.step, 0);
    EXPECT_EQ(c.id.size(), 4000u);
    const std::string rest = long_melt(dir, "rest", c.step + 20);
    const std::string restart = std::string(DELI_BINARY) + " run " + rest + " --restart " + dir +
                                "/stop.h5 > " + dir + "/rest.log 2>&1";
    EXPECT_EQ(std::system(restart.c_str()), 0) << "SIG" << signal;
    std::ifstream log(dir + "/rest.log");
    const std::string text((std::istreambuf_iterator<char>(log)), {});
    EXPECT_NE(text.find("for 20 steps"), std::string::npos) << text;
  }
}

// SIGKILL at an arbitrary moment: no handler runs, nothing is closed. The trajectory must
// open (h5py, MDAnalysis) and hold every frame flushed before the kill: at least every
// frame whose thermo row reached the CSV (rows are written after their frames).
TEST(Checkpoint, SigkillLeavesAReadableTrajectory) {
  const std::string dir = deli::testing::process_temp_dir() + "/killed_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  const std::string input = dir + "/long.toml";
  std::ofstream(input)
      << "[system]\ndata = \"" DELI_SOURCE_DIR
         "/inputs/lj_chains/melt.data\"\n"
         "[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n"
         "[forcefield.pair]\nstyle = \"wca\"\n"
         "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
         "[forcefield.bond]\nstyle = \"fene\"\n"
         "coeffs = [{ type = 1, k = 30.0, r0 = 1.5, epsilon = 1.0, sigma = 1.0 }]\n"
         "[integrator]\ntimestep = 0.005\n[run]\nsteps = 100000000\n"
         "[output]\nthermo = { every = 10, file = \""
      << dir << "/run.csv\" }\ntrajectory = { file = \"" << dir
      << "/run.h5\", every = 10, forces = true }\n";
  const std::string command = "sh -c '" + std::string(DELI_BINARY) + " run " + input + " > " + dir +
                              "/run.log 2>&1 & pid=$!; " + wait_for_first_row(dir + "/run.log") +
                              "sleep 0.5; kill -KILL $pid; wait $pid; " +
                              "/usr/bin/python3 " DELI_SOURCE_DIR "/tests/io/killed_run_check.py " +
                              dir + "/run.h5 " + dir +
                              "/run.csv 10 " DELI_SOURCE_DIR "/inputs/lj_chains/melt.data 2>&1'";
  const testing::ShellResult r = testing::run_shell(command);
  std::printf("%s", r.output.c_str());
  EXPECT_EQ(r.status, 0) << r.output;
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// A point resting on a floor under gravity: the collision integrator meets a contact at
// every instant of its first step (Zeno), and with a huge event cap that step never ends.
std::string resting_point(const std::string& dir) {
  std::ofstream(dir + "/rest.data") << "resting point\n\n1 atoms\n1 atom types\n\n-10 10 xlo xhi\n"
                                       "-10 10 ylo yhi\n-10 10 zlo zhi\n\nMasses\n\n1 1\n\n"
                                       "Atoms # atomic\n\n1 1 0 0 0\n";
  const std::string input = dir + "/zeno.toml";
  std::ofstream(input) << "[system]\ndata = \"rest.data\"\nboundary = \"fff\"\n"
                          "[forcefield.pair]\nstyle = \"none\"\n[forcefield.external]\n"
                          "gravity = [0, 0, -9.8]\n[constraints]\n"
                          "walls = [{ type = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }]\n"
                          "[integrator]\ntype = \"collision\"\ntimestep = 0.01\n"
                          "max_events_per_step = 2000000000\n[run]\nsteps = 10\n";
  return input;
}

// The signal is checked inside the step: the run stops (status 3, the step named) instead of
// ignoring SIGINT until the step ends, which it never does.
TEST(Checkpoint, SignalStopsAStepThatDoesNotEnd) {
  const std::string dir = deli::testing::process_temp_dir() + "/zeno_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  const std::string command = "sh -c '" + std::string(DELI_BINARY) + " run " + resting_point(dir) +
                              " > " + dir + "/run.log 2>&1 & pid=$!; " +
                              wait_for_first_row(dir + "/run.log") +
                              "kill -INT $pid; wait $pid; echo $?'";
  EXPECT_EQ(testing::run_shell(command).output, "3\n");  // the simulation stopped
  std::ifstream log(dir + "/run.log");
  const std::string text((std::istreambuf_iterator<char>(log)), {});
  EXPECT_NE(text.find("interrupted during step 1"), std::string::npos) << text;
}

// A second signal (here SIGTERM after SIGINT: two different signals are both delivered)
// ends the process at once, without waiting for the step and the checkpoint. Both are sent
// while the process is stopped (SIGSTOP), so both are pending when it continues: sent to a
// running process, the first could be honoured, step and checkpoint, before the second came.
TEST(Checkpoint, SecondSignalStopsAtOnce) {
  const std::string dir =
      deli::testing::process_temp_dir() + "/second_signal_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  const std::string command = "sh -c '" + std::string(DELI_BINARY) + " run " +
                              long_melt(dir, "long", 100000000) + " > " + dir +
                              "/run.log 2>&1 & pid=$!; " + wait_for_first_row(dir + "/run.log") +
                              "kill -STOP $pid; kill -INT $pid; kill -TERM $pid; kill -CONT $pid; "
                              "wait $pid; echo $?'";
  EXPECT_EQ(testing::run_shell(command).output, "130\n");
  std::ifstream log(dir + "/run.log");
  const std::string text((std::istreambuf_iterator<char>(log)), {});
  EXPECT_NE(text.find("second interrupt"), std::string::npos) << text;
}

// Without a configured checkpoint the interrupt's checkpoint goes to the working directory
// (the input's may be read-only), and the message says where.
TEST(Checkpoint, InterruptCheckpointGoesToTheWorkingDirectory) {
  const std::string dir =
      deli::testing::process_temp_dir() + "/interrupt_cwd_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir + "/input " + dir + "/work").c_str());
  const std::string input = dir + "/input/plain.toml";
  std::ofstream(input) << "[system]\ndata = \"" DELI_SOURCE_DIR
                          "/inputs/lj_chains/melt.data\"\n"
                          "[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n"
                          "[forcefield.pair]\nstyle = \"wca\"\n"
                          "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
                          "[forcefield.bond]\nstyle = \"fene\"\n"
                          "coeffs = [{ type = 1, k = 30.0, r0 = 1.5, epsilon = 1.0, sigma = 1.0 "
                          "}]\n[integrator]\ntimestep = 0.005\n[run]\nsteps = 100000000\n";
  const std::string command = "sh -c 'cd " + dir + "/work && " + std::string(DELI_BINARY) +
                              " run " + input + " > run.log 2>&1 & pid=$!; " +
                              wait_for_first_row(dir + "/work/run.log") +
                              "kill -INT $pid; wait $pid; echo $?'";
  EXPECT_EQ(testing::run_shell(command).output, "130\n");
  EXPECT_GT(read_checkpoint(dir + "/work/plain.toml.interrupted.h5").step, 0);
  EXPECT_FALSE(std::ifstream(dir + "/input/plain.toml.interrupted.h5").good());
  std::ifstream log(dir + "/work/run.log");
  const std::string text((std::istreambuf_iterator<char>(log)), {});
  EXPECT_NE(text.find(dir.substr(dir.rfind('/')) + "/work/plain.toml.interrupted.h5"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace deli
