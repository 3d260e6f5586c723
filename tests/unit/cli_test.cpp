// The deli executable as a user meets it: help, version, one-line errors, exit codes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <string>

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
  const std::string dir = ::testing::TempDir();
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
