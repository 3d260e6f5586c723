// Unlike LJ pairs that the input does not give are mixed as LAMMPS' pair lj/cut mixes them
// by default (pair_modify mix geometric): LAMMPS itself, given only the like pairs, is the
// reference.
#include <gtest/gtest.h>
#include <library.h>

#include <cmath>

#include "crosscheck/single_process_mpi.hpp"
#include "input/lammps_data.hpp"
#include "support/process_temp_dir.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

double lammps_potential_energy(const System& system, const std::string& data) {
  write_lammps_data(system, data, "atomic", "deli mixing test");
  const char* args[] = {"deli", "-screen", "none", "-log", "none", "-nocite"};
  deli::prefer_single_process_mpi();
  void* lmp = lammps_open_no_mpi(6, const_cast<char**>(args), nullptr);
  for (const std::string line : std::vector<std::string>{
           "units lj", "atom_style atomic", "read_data " + data, "pair_style lj/cut 2.5",
           "pair_coeff 1 1 1.0 1.0", "pair_coeff 2 2 0.6 1.3 3.0", "run 0"}) {
    lammps_command(lmp, line.c_str());
  }
  const double pe = lammps_get_thermo(lmp, "pe") * static_cast<double>(system.particles.size());
  lammps_close(lmp);
  return pe;
}

TEST(Mixing, DefaultIsLammpsGeometric) {
  const std::string mixture =
      "[system]\n[system.lattice]\ntype = \"fcc\"\ndensity = 0.8\ncells = [5, 5, 5]\ntypes = 2\n"
      "masses = [1.0, 2.5]\n[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\n";
  const std::string like =
      "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 },\n"
      "          { types = [2, 2], epsilon = 0.6, sigma = 1.3, cutoff = 3.0 }]\n"
      "[integrator]\ntimestep = 0.004\n[run]\nsteps = 0\n";
  RunInput input = testing::input_from(mixture + like);
  testing::jiggle(input.system.particles, 0.1, 5);
  const double deli = testing::evaluate(input).evaluation.potential;
  const double lammps =
      lammps_potential_energy(input.system, deli::testing::process_temp_dir() + "/mixture.data");
  std::printf("deli %.12g, LAMMPS %.12g\n", deli, lammps);
  EXPECT_NEAR(deli, lammps, 1e-10 * std::abs(lammps));
  // Lorentz-Berthelot stays selectable, and differs.
  RunInput arithmetic = testing::input_from(mixture + "mixing = \"arithmetic\"\n" + like);
  arithmetic.system.particles.position = input.system.particles.position;
  EXPECT_GT(std::abs(testing::evaluate(arithmetic).evaluation.potential - lammps),
            1e-3 * std::abs(lammps));
}

}  // namespace
}  // namespace deli
