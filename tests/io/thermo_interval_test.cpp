// How often the thermo table is written must not change the trajectory: a row observes the
// state, it does not steer it. GVI's impact_time contact step restores the energy of its
// start; that energy was reused from the previous step's end when that step had tallied
// energies, which only thermo steps do, and that tally could have summed over the neighbour
// list before a rebuild, in another order. The paper's LJ chain (bench/contact_energy: six
// beads on five rods, hard cores on LJ's wall, in a sphere) at h = 0.01, seed 1001, was found
// to part in the last bits at step 17472 (a contact right after such a rebuild), between
// thermo every step and every 50 steps. Expected value: identical rows, by definition.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"

namespace deli {
namespace {

std::string chain_input(const std::string& dir, int every) {
  const std::string path = dir + "/every" + std::to_string(every) + ".toml";
  std::ofstream(path)
      << "[system]\ndata = \"" DELI_SOURCE_DIR "/bench/contact_energy/chain.data\"\n"
      << "boundary = \"fff\"\n[velocities]\ntemperature = 0.13\nseed = 1001\n"
      << "[forcefield.special_bonds]\nlj = [1.0, 1.0, 1.0]\n[constraints]\nrods = ["
      << "{ atoms = [1, 2], length = 1.0 }, { atoms = [2, 3], length = 1.0 }, "
      << "{ atoms = [3, 4], length = 1.0 }, { atoms = [4, 5], length = 1.0 }, "
      << "{ atoms = [5, 6], length = 1.0 }]\n"
      << "hard_spheres = { diameter = 0.6 }\n"
      << "walls = [{ type = \"inside_sphere\", radius = 5.0 }]\n"
      << "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 3.0\n"
      << "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 0.6 }]\n"
      << "[integrator]\ntype = \"gvi\"\ntimestep = 0.01\ncontact = \"impact_time\"\n"
      << "[run]\nsteps = 17500\n[output]\nthermo = { every = " << every << ", file = \"" << dir
      << "/every" << every << ".csv\" }\n";
  return path;
}

// Per step: the state's columns of a thermo CSV (interval statistics such as the pressure,
// the smallest gap and the solver counts differ by design between intervals).
std::map<std::string, std::string> state_rows(const std::string& path) {
  const std::vector<std::string> state = {"kinetic", "potential", "total", "px", "py",
                                          "pz",      "Lx",        "Ly",    "Lz", "shadow_energy"};
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  for (std::stringstream s(line); std::getline(s, line, ',');) header.push_back(line);
  std::map<std::string, std::string> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    for (std::stringstream s(line); std::getline(s, line, ',');) fields.push_back(line);
    std::string kept;
    for (std::size_t k = 0; k < header.size() && k < fields.size(); ++k) {
      for (const std::string& name : state) {
        if (header[k] == name) kept += name + "=" + fields[k] + " ";
      }
    }
    rows[fields.front()] = kept;
  }
  return rows;
}

TEST(ThermoInterval, DoesNotChangeTheTrajectory) {
  const std::string dir = testing::process_temp_dir() + "/thermo_interval";
  ASSERT_EQ(testing::run_shell("rm -rf " + dir + " && mkdir -p " + dir).status, 0);
  for (int every : {1, 50}) {
    const testing::ShellResult run =
        testing::run_shell(std::string(DELI_BINARY) + " run " + chain_input(dir, every));
    ASSERT_EQ(run.status, 0) << run.output;
  }
  const auto every_step = state_rows(dir + "/every1.csv");
  const auto every_50 = state_rows(dir + "/every50.csv");
  ASSERT_EQ(every_step.size(), 17501u);
  ASSERT_EQ(every_50.size(), 351u);
  for (const auto& [step, row] : every_50) {
    ASSERT_EQ(every_step.at(step), row) << "step " << step;
  }
}

}  // namespace
}  // namespace deli
