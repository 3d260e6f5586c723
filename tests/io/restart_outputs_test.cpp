// `deli run --restart` continues the run's outputs: the thermo CSV, the H5MD trajectory
// (still H5MD 1.1, its shared step and time extended once per frame) and the dump (XYZ or
// LAMMPS) of a run stopped at a checkpoint (and run on past it, frames the restart
// must drop) and then restarted are those of the uninterrupted run, bit for bit.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>

#include "support/file_contents.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"

namespace deli {
namespace {

int shell(const std::string& command, std::string& output) {
  const testing::ShellResult r = testing::run_shell(command);
  output = r.output;
  return r.status;
}

// The default input (GVI: rods, hard cores, walls) with its own run length and outputs.
std::string slit_input(const std::string& dir, const std::string& name, int steps) {
  std::string text = testing::file_contents(DELI_SOURCE_DIR "/inputs/lj_chains/rigid_slit.toml");
  text = text.substr(0, text.find("[run]"));
  text.replace(text.find("\"rigid_slit.data\""), 17,
               "\"" DELI_SOURCE_DIR "/inputs/lj_chains/rigid_slit.data\"");
  const std::string path = dir + "/" + name + ".toml";
  std::ofstream(path) << text << "[run]\nsteps = " << steps << "\n[output]\n"
                      << "thermo = { every = 20, file = \"" << dir << "/out.csv\" }\n"
                      << "trajectory = { file = \"" << dir << "/out.h5\", every = 20, "
                      << "forces = true }\n"
                      << "dump = { file = \"" << dir
                      << "/out.dump\", every = 40, format = \"xyz\" }\n"
                      << "checkpoint = { file = \"" << dir << "/out.chk\", every = 100 }\n";
  return path;
}

TEST(Restart, OutputsContinueBitForBit) {
  const std::string root = deli::testing::process_temp_dir() + "/restart_outputs";
  std::string log;
  ASSERT_EQ(
      shell("rm -rf " + root + " && mkdir -p " + root + "/straight " + root + "/stopped", log), 0);
  const std::string deli = DELI_BINARY;
  ASSERT_EQ(shell(deli + " run " + slit_input(root + "/straight", "run", 200), log), 0) << log;
  // Stopped: runs to 140 (its last checkpoint at 100), then is restarted to 200: the
  // frames and rows from 100 on are cut and written again.
  const std::string stopped = root + "/stopped";
  ASSERT_EQ(shell(deli + " run " + slit_input(stopped, "first", 140), log), 0) << log;
  ASSERT_EQ(shell(deli + " run " + slit_input(stopped, "second", 200) + " --restart " + stopped +
                      "/out.chk",
                  log),
            0)
      << log;
  EXPECT_EQ(testing::file_contents(root + "/straight/out.csv"),
            testing::file_contents(stopped + "/out.csv"));
  EXPECT_EQ(testing::file_contents(root + "/straight/out.dump"),
            testing::file_contents(stopped + "/out.dump"));
  ASSERT_EQ(shell("/usr/bin/python3 " DELI_SOURCE_DIR "/tests/io/compare_h5md.py " + root +
                      "/straight/out.h5 " + stopped + "/out.h5 11",
                  log),
            0)
      << log;
  std::printf("%s", log.c_str());
  // The appended file is still H5MD 1.1, its series still sharing one step and time.
  EXPECT_EQ(shell("/usr/bin/python3 " DELI_SOURCE_DIR "/tests/io/h5md_conformance.py --deli " +
                      stopped + "/out.h5",
                  log),
            0)
      << log;
  std::printf("%s", log.c_str());
  EXPECT_EQ(shell("/usr/bin/python3 " DELI_SOURCE_DIR "/tests/io/extxyz_check.py " + stopped +
                      "/out.dump",
                  log),
            0)
      << log;
  EXPECT_NE(log.find("6 frames"), std::string::npos) << log;
  // The GVI trajectory carries the rods and the constraint statistics; the plot tool draws
  // them.
  ASSERT_EQ(
      shell("/usr/bin/python3 -c \"import h5py; f = h5py.File('" + stopped +
                "/out.h5'); print(f['connectivity/rods'].shape, "
                "f['observables/min_gap/value'].shape, f['observables/reflected/value'][:].sum() "
                "> 0)\"",
            log),
      0)
      << log;
  EXPECT_NE(log.find("(1140, 2) (11,) True"), std::string::npos) << log;
  ASSERT_EQ(shell("/usr/bin/python3 " DELI_SOURCE_DIR "/tools/plot_h5md.py " + stopped +
                      "/out.h5 " + stopped + "/out.png",
                  log),
            0)
      << log;
  EXPECT_NE(log.find("constraint events"), std::string::npos) << log;
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// An input of the repository with its data file made absolute and its [run] and [output]
// replaced: thermo rows every 20 steps, H5MD frames every 25, dump frames every 30 and a
// checkpoint every 37 and at the end (a run of 91 steps ends with one at 91, a multiple of
// none of them). With `sort_every`, the particles sorted in space that often (else as the
// input says: by default every 1000 steps, here at the start only).
std::string with_outputs(const std::string& source, const std::string& dir, int steps,
                         int sort_every = 0) {
  std::string text = testing::file_contents(std::string(DELI_SOURCE_DIR) + "/" + source);
  text = text.substr(0, text.find("[run]"));
  if (sort_every > 0) {
    const std::string key = "sort_every = " + std::to_string(sort_every) + "\n";
    const auto neighbor = text.find("[neighbor]\n");
    if (neighbor == std::string::npos) {
      text += "[neighbor]\n" + key;
    } else {
      text.insert(neighbor + 11, key);
    }
  }
  const std::string source_dir =
      std::string(DELI_SOURCE_DIR) + "/" + source.substr(0, source.rfind('/') + 1);
  const auto data = text.find("data = \"");
  if (data != std::string::npos) text.insert(data + 8, source_dir);
  const std::string path = dir + "/run" + std::to_string(steps) + ".toml";
  std::ofstream(path) << text << "[run]\nsteps = " << steps << "\n[output]\n"
                      << "thermo = { every = 20, file = \"" << dir << "/out.csv\" }\n"
                      << "trajectory = { file = \"" << dir << "/out.h5\", every = 25 }\n"
                      << "dump = { file = \"" << dir << "/out.dump\", every = 30 }\n"
                      << "checkpoint = { file = \"" << dir << "/out.chk\", every = 37 }\n";
  return path;
}

// A restart from a step that is a multiple of no output interval (91, the end of the
// stopped run) writes the rows and frames of the uninterrupted run, for every integrator:
// rows at absolute multiples of `every` (and the last step), not counted from the restart,
// and the stopped run's last row (at 91) dropped.
// With the particles sorted in space every 40 steps, the stopped run's checkpoint holds them
// in the order of step 80, and the restart sorts them again at 120.
class RestartFromAnyStep : public ::testing::TestWithParam<std::tuple<std::string, int>> {};

TEST_P(RestartFromAnyStep, OutputsEqualTheUninterruptedRun) {
  const auto& [input, sort_every] = GetParam();
  const std::string name = input.substr(input.rfind('/') + 1) + std::to_string(sort_every);
  const std::string root = deli::testing::process_temp_dir() + "/restart_any_" + name;
  std::string log;
  ASSERT_EQ(
      shell("rm -rf " + root + " && mkdir -p " + root + "/straight " + root + "/stopped", log), 0);
  const std::string deli = DELI_BINARY;
  ASSERT_EQ(shell(deli + " run " + with_outputs(input, root + "/straight", 150, sort_every), log),
            0)
      << log;
  const std::string stopped = root + "/stopped";
  ASSERT_EQ(shell(deli + " run " + with_outputs(input, stopped, 91, sort_every), log), 0) << log;
  EXPECT_NE(testing::file_contents(stopped + "/out.csv").find("\n91,"), std::string::npos);
  ASSERT_EQ(shell(deli + " run " + with_outputs(input, stopped, 150, sort_every) + " --restart " +
                      stopped + "/out.chk",
                  log),
            0)
      << log;
  EXPECT_NE(log.find("for 59 steps"), std::string::npos) << log;  // from 91 to 150
  if (sort_every > 0) {
    EXPECT_NE(log.find("particles sorted in space"), std::string::npos) << log;
  }
  const std::string csv = testing::file_contents(root + "/straight/out.csv");
  EXPECT_NE(csv.find("\n140,"), std::string::npos);  // rows at multiples of 20, and 150
  EXPECT_NE(csv.find("\n150,"), std::string::npos);
  EXPECT_EQ(csv, testing::file_contents(stopped + "/out.csv"));
  EXPECT_EQ(testing::file_contents(root + "/straight/out.dump"),
            testing::file_contents(stopped + "/out.dump"));
  EXPECT_EQ(shell("/usr/bin/python3 " DELI_SOURCE_DIR "/tests/io/compare_h5md.py " + root +
                      "/straight/out.h5 " + stopped + "/out.h5 7",
                  log),
            0)
      << log;
  EXPECT_EQ(shell("/usr/bin/python3 " DELI_SOURCE_DIR "/tests/io/h5md_conformance.py --deli " +
                      stopped + "/out.h5",
                  log),
            0)
      << log;
}

INSTANTIATE_TEST_SUITE_P(
    EveryIntegrator, RestartFromAnyStep,
    ::testing::Combine(
        ::testing::Values("inputs/lj_chains/melt.toml", "inputs/lj_chains/rigid_slit.toml",
                          "inputs/paper/baselines/newtons_cradle_direct_endpoint.toml",
                          "inputs/paper/baselines/pogo_stick_collision.toml"),
        ::testing::Values(0, 40)),
    [](const ::testing::TestParamInfo<std::tuple<std::string, int>>& info) {
      const std::string& path = std::get<0>(info.param);
      const std::string file = path.substr(path.rfind('/') + 1);
      const int sort_every = std::get<1>(info.param);
      return file.substr(0, file.find('.')) +
             (sort_every > 0 ? "_sorted_every_" + std::to_string(sort_every) : "");
    });

}  // namespace
}  // namespace deli
