// The deli executable as a user meets it: help, version, one-line errors, exit codes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "support/file_contents.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"

namespace {

using ::testing::HasSubstr;

using Result = deli::testing::ShellResult;

Result run_deli(const std::string& arguments) {
  return deli::testing::run_shell(std::string(DELI_BINARY) + " " + arguments);
}

TEST(Cli, HelpListsCommands) {
  const Result r = run_deli("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_THAT(r.output, HasSubstr("run [INPUT]"));
}

TEST(Cli, Version) {
  const Result r = run_deli("--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_THAT(r.output, HasSubstr("deli 0."));
}

TEST(Cli, MissingInputIsOneLineAndNonZero) {
  const Result r = run_deli("run /nonexistent/case.toml");
  EXPECT_NE(r.status, 0);
  EXPECT_THAT(r.output, HasSubstr("/nonexistent/case.toml"));
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

TEST(Cli, UnknownCommand) {
  const Result r = run_deli("rnu");
  EXPECT_NE(r.status, 0);
  EXPECT_THAT(r.output, HasSubstr("unknown command 'rnu'"));
}

// A short run of a real input: thermo table on stdout, CSV written, no progress line
// when the output is not a terminal.
TEST(Cli, RunsAnInputAndWritesThermo) {
  const std::string dir = deli::testing::process_temp_dir();
  const std::string input = dir + "/short.toml";
  std::ofstream(input) << "[system]\ndata = \"" DELI_SOURCE_DIR
                          "/inputs/lj_liquid/lj_4000.data\"\n"
                          "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n"
                          "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
                          "[integrator]\ntimestep = 0.005\n[run]\nsteps = 20\n"
                          "[output]\nthermo = { every = 10, file = \""
                       << dir << "/short.csv\" }\n";
  const Result r = run_deli(input);
  EXPECT_NE(r.status, 0) << "a bare path is not a command";
  const Result ok = run_deli("run " + input);
  ASSERT_EQ(ok.status, 0) << ok.output;
  EXPECT_THAT(ok.output, HasSubstr("temperature"));
  EXPECT_THAT(ok.output, ::testing::Not(HasSubstr("ETA")));
  // The LAMMPS thermo of the same start (lmp -in in.lj_4000): step 0 total energy.
  EXPECT_THAT(ok.output, HasSubstr("-18455.632"));
  std::ifstream csv(dir + "/short.csv");
  std::string header, line;
  std::getline(csv, header);
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_THAT(header, HasSubstr("step,time,kinetic,potential,total,temperature,pressure"));
  EXPECT_EQ(rows, 3);
}

}  // namespace

namespace {

// Rigid 4-mers whose velocities are drawn at T = 0.988: the run starts at 0.988 counted
// with 3N - rods - 3 degrees of freedom (the README's rule), and the trajectory and
// `deli info` carry the same count. Before the count, deli reported 0.741 (3N - 3, and
// the projection onto the rods removed their share after the draw).
TEST(Cli, ConstrainedRunStartsAtItsTemperatureWithItsDegreesOfFreedom) {
  const std::string dir = deli::testing::process_temp_dir();
  const std::string input = dir + "/rigid4.toml";
  std::ofstream(input) << "[system]\n[system.chains]\ncount = 25\nlength = 4\ndensity = 0.5\n"
                          "bond_length = 1.0\nmin_distance = 0.95\nseed = 3\n"
                          "[velocities]\ntemperature = 0.988\nseed = 5\n"
                          "[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n"
                          "[forcefield.pair]\nstyle = \"wca\"\n"
                          "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
                          "[constraints]\nbonds = \"rigid\"\n"
                          "[integrator]\ntype = \"gvi\"\ntimestep = 0.004\n[run]\nsteps = 10\n"
                          "[output]\nthermo = { every = 10, file = \""
                       << dir << "/rigid4.csv\" }\ntrajectory = { file = \"" << dir
                       << "/rigid4.h5\", every = 5 }\n";
  const Result r = run_deli("run " + input);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("degrees of freedom 222 = 3 x 100 atoms - 75 rods/strings - 3"));
  std::ifstream csv(dir + "/rigid4.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  std::vector<std::string> fields;
  std::string field;
  for (std::istringstream row(first); std::getline(row, field, ',');) fields.push_back(field);
  ASSERT_GT(fields.size(), 5u);
  EXPECT_NEAR(std::stod(fields[5]), 0.988, 1e-12) << first;  // temperature at step 0
  const Result info = run_deli("info " + dir + "/rigid4.h5");
  ASSERT_EQ(info.status, 0) << info.output;
  EXPECT_THAT(info.output, HasSubstr("222 degrees of freedom"));
}

}  // namespace

namespace {

// README "Exit status": one status per kind of outcome.
TEST(Cli, ExitStatusTellsTheKindOfOutcome) {
  EXPECT_EQ(run_deli("").status, 2);                       // usage
  EXPECT_EQ(run_deli("rnu").status, 2);                    // unknown command
  EXPECT_EQ(run_deli("run /nonexistent.toml").status, 1);  // input error
  const std::string dir = deli::testing::process_temp_dir();
  std::ofstream(dir + "/blowup.toml")
      << "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.8442\ncells = [3, 3, 3]\n"
         "[velocities]\ntemperature = 1.0\nseed = 1\n[forcefield.pair]\nstyle = \"lj/cut\"\n"
         "cutoff = 2.5\ncoeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
         "[integrator]\ntimestep = 0.5\n[run]\nsteps = 100\n";
  const Result blowup = run_deli("run " + dir + "/blowup.toml");
  EXPECT_EQ(blowup.status, 3) << blowup.output;  // the simulation stopped
  EXPECT_THAT(blowup.output, HasSubstr("simulation stopped"));
}

// What LAMMPS users expect at the end of a run: a checkpoint when the run has them (here
// every 7 steps, the run ends at 10), the final state as a data file that deli reads back,
// and a log holding what the terminal showed.
TEST(Cli, RunEndsWithCheckpointFinalDataAndLog) {
  const std::string dir = deli::testing::process_temp_dir() + "/run_end";
  ASSERT_EQ(deli::testing::run_shell("rm -rf " + dir + " && mkdir -p " + dir).status, 0);
  const std::string system =
      "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.8442\ncells = [3, 3, 3]\n"
      "[velocities]\ntemperature = 1.0\nseed = 1\n";
  const std::string model =
      "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n"
      "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n"
      "[integrator]\ntimestep = 0.005\n";
  std::ofstream(dir + "/in.toml") << system << model << "[run]\nsteps = 10\n[output]\n"
                                  << "thermo = { every = 5 }\ncheckpoint = { file = \"" << dir
                                  << "/c.h5\", every = 7 }\nfinal_data = \"" << dir
                                  << "/final.data\"\nlog = \"" << dir << "/run.log\"\n";
  const Result r = run_deli("run " + dir + "/in.toml");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("final checkpoint at step 10"));
  const Result info = run_deli("info " + dir + "/c.h5");
  EXPECT_THAT(info.output, HasSubstr("at step 10")) << info.output;
  // The log is the terminal's output (stdout), line for line.
  EXPECT_EQ(deli::testing::file_contents(dir + "/run.log"), r.output);
  // The final state read back: a 0-step run from it starts where the first run ended.
  std::ofstream(dir + "/again.toml") << "[system]\ndata = \"final.data\"\n"
                                     << model << "[run]\nsteps = 0\n";
  const Result again = run_deli("run " + dir + "/again.toml");
  ASSERT_EQ(again.status, 0) << again.output;
  // Kinetic and potential energy of the first run's last row and the second run's first.
  auto energies = [](const std::string& output, const std::string& step) {
    std::istringstream row(
        output.substr(output.find("\n" + std::string(10 - step.size(), ' ') + step + " ")));
    std::string s, time, kinetic, potential;
    row >> s >> time >> kinetic >> potential;
    return kinetic + " " + potential;
  };
  EXPECT_EQ(energies(again.output, "0"), energies(r.output, "10"));
}

}  // namespace
