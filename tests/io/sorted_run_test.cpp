// `[neighbor] sort_every`: a run whose particles are put in spatial order every few steps
// follows the trajectory of the same run without sorting, to rounding (a relabelling
// changes only the order of sums), and writes its thermo rows, H5MD frames and dump lines
// for the atoms in the input's order. Expected values: the run with sort_every = 0.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/csv_numbers.hpp"
#include "support/file_contents.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"

namespace deli {
namespace {

// An input of the repository with its data file made absolute, sorted every `sort_every`
// steps, run for 60 steps with thermo rows every 5, H5MD frames (velocities too) every 20,
// LAMMPS dump frames every 30 and the final state as a data file.
std::string sorted_input(const std::string& source, const std::string& dir, int sort_every,
                         const std::string& replace = "", const std::string& by = "") {
  std::string text = testing::file_contents(std::string(DELI_SOURCE_DIR) + "/" + source);
  text = text.substr(0, text.find("[run]"));
  if (!replace.empty()) text.replace(text.find(replace), replace.size(), by);
  const auto data = text.find("data = \"");
  if (data != std::string::npos) {
    text.insert(data + 8,
                std::string(DELI_SOURCE_DIR) + "/" + source.substr(0, source.rfind('/') + 1));
  }
  text.insert(text.find("[neighbor]\n") + 11, "sort_every = " + std::to_string(sort_every) + "\n");
  const std::string path = dir + "/run.toml";
  testing::run_shell("mkdir -p " + dir);
  std::ofstream(path) << text << "[run]\nsteps = 60\n[output]\n"
                      << "thermo = { every = 5, file = \"" << dir << "/out.csv\" }\n"
                      << "trajectory = { file = \"" << dir
                      << "/out.h5\", every = 20, velocities = true }\n"
                      << "dump = { file = \"" << dir << "/out.dump\", every = 30 }\n"
                      << "final_data = \"" << dir << "/final.data\"\n";
  return path;
}

// A data file's atom ids in the order of its Atoms section, then its Bonds section's lines.
std::vector<std::string> ids_and_bonds(const std::string& data) {
  std::vector<std::string> out;
  std::istringstream lines(data);
  std::string section;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("Atoms", 0) == 0 || line.rfind("Bonds", 0) == 0 ||
        line.rfind("Velocities", 0) == 0 || line.rfind("Masses", 0) == 0) {
      section = line.substr(0, 5);
      continue;
    }
    if (line.empty()) continue;
    if (section == "Atoms") out.push_back(line.substr(0, line.find(' ')));
    if (section == "Bonds") out.push_back(line);
  }
  return out;
}

// The atom ids of a LAMMPS dump's lines, frame after frame.
std::vector<long long> dump_ids(const std::string& dump) {
  std::vector<long long> ids;
  std::istringstream lines(dump);
  bool atoms = false;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("ITEM:", 0) == 0) {
      atoms = line.rfind("ITEM: ATOMS", 0) == 0;
      continue;
    }
    if (atoms) ids.push_back(std::stoll(line));
  }
  return ids;
}

void expect_sorted_run_follows_unsorted(const std::string& name, const std::string& source,
                                        const std::string& replace = "",
                                        const std::string& by = "") {
  const std::string root =
      testing::process_temp_dir() + "/sorted_" + name + "_" + std::to_string(getpid());
  const testing::ShellResult unsorted = testing::run_shell(
      DELI_BINARY " run " + sorted_input(source, root + "/unsorted", 0, replace, by));
  ASSERT_EQ(unsorted.status, 0) << unsorted.output;
  EXPECT_EQ(unsorted.output.find("particles sorted"), std::string::npos) << unsorted.output;
  const testing::ShellResult sorted = testing::run_shell(
      DELI_BINARY " run " + sorted_input(source, root + "/sorted", 7, replace, by));
  ASSERT_EQ(sorted.status, 0) << sorted.output;
  // At the start and at steps 7, 14, ..., 56 (a sort that finds the order unchanged does not
  // count): a fluid's particles change bins within a few steps.
  const auto said = sorted.output.find("particles sorted in space ");
  ASSERT_NE(said, std::string::npos) << sorted.output;
  EXPECT_GE(std::stoi(sorted.output.substr(said + 26)), 5) << sorted.output;

  // Thermo rows (kinetic, potential, total, pressure): to rounding, grown by the dynamics
  // over 60 steps.
  const auto a = testing::csv_numbers(testing::file_contents(root + "/unsorted/out.csv"));
  const auto b = testing::csv_numbers(testing::file_contents(root + "/sorted/out.csv"));
  ASSERT_EQ(a.size(), 13u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t r = 0; r < a.size(); ++r) {
    for (std::size_t c = 2; c <= 6; ++c) {
      EXPECT_NEAR(b[r][c], a[r][c], 1e-9 * (1.0 + std::abs(a[r][c])))
          << "row " << r << " col " << c;
    }
  }
  // The trajectory's atoms in the input's order: the same ids, positions and velocities row
  // by row.
  const testing::ShellResult frames = testing::run_shell(
      "/usr/bin/python3 -c \"import h5py, numpy as np, sys\n"
      "a = h5py.File(sys.argv[1], 'r')['particles/all']\n"
      "b = h5py.File(sys.argv[2], 'r')['particles/all']\n"
      "assert (a['id'][()] == b['id'][()]).all(), 'ids'\n"
      "assert (np.diff(a['id'][()]) > 0).all(), 'the input lists its atoms by id'\n"
      "assert a['position/value'].shape[0] == 4, 'frames'\n"
      "for s in ('position', 'velocity'):\n"
      "    d = np.abs(a[s + '/value'][()] - b[s + '/value'][()]).max()\n"
      "    assert d < 1e-9, (s, d)\n\" " +
      root + "/unsorted/out.h5 " + root + "/sorted/out.h5");
  EXPECT_EQ(frames.status, 0) << frames.output;
  const std::vector<long long> ids = dump_ids(testing::file_contents(root + "/unsorted/out.dump"));
  EXPECT_FALSE(ids.empty());
  EXPECT_EQ(ids, dump_ids(testing::file_contents(root + "/sorted/out.dump")));
  // The final data file: the atoms in the input's order, the same bonds between the same ids.
  const std::vector<std::string> final_atoms =
      ids_and_bonds(testing::file_contents(root + "/unsorted/final.data"));
  EXPECT_GT(final_atoms.size(), 100u);
  EXPECT_EQ(final_atoms, ids_and_bonds(testing::file_contents(root + "/sorted/final.data")));
  testing::run_shell("rm -rf " + root);
}

TEST(SortedRun, HardSphereFluidFollowsTheUnsortedTrajectory) {
  expect_sorted_run_follows_unsorted("hs", "inputs/hard_spheres/hs_500.toml");
}

// The default input with Hamiltonian reflections: its shadow-energy restorations find the
// energy to restore as a difference of sums over all atoms (about 1e3 each), whose rounding
// (any regrouping's, as sorting's) reaches 1e-9 of the pressure at the first impact (step 2)
// and 1e-6 by step 42; with Hamiltonian reflections sorted and unsorted agree to 5e-13 over
// 60 steps.
TEST(SortedRun, RodChainsBetweenWallsFollowTheUnsortedTrajectory) {
  expect_sorted_run_follows_unsorted("slit", "inputs/lj_chains/rigid_slit.toml",
                                     "energy = \"shadow\"", "energy = \"hamiltonian\"");
}

}  // namespace
}  // namespace deli
