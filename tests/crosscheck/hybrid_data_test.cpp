// A data file whose Bond Coeffs mix styles (LAMMPS' hybrid: "Bond Coeffs # hybrid", each
// row naming its style, the form read_data takes) runs in deli with the coefficients it
// carries: the same energy as the model with every coefficient in the TOML, and as LAMMPS'
// own read_data of the same file. The file is written here, not by LAMMPS: Debian 12's
// LAMMPS (29 Sep 2021) writes no coefficient section for a hybrid style (BondHybrid has
// writedata = 0), so LAMMPS reading it is the reference for its form.
#include <gtest/gtest.h>
#include <library.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "crosscheck/single_process_mpi.hpp"
#include "support/process_temp_dir.hpp"
#include "support/source_tree.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

using testing::kSource;
const std::string kHybridCoeffs =
    "Bond Coeffs # hybrid\n\n1 fene 30.0 1.5 1.0 1.0\n2 harmonic 100.0 0.97\n\n";

// tests/crosscheck/inputs/mixed_bonds.data (FENE type 1, harmonic type 2) with the hybrid
// section before its Atoms.
std::string write_hybrid_data() {
  std::ifstream in(kSource + "/tests/crosscheck/inputs/mixed_bonds.data");
  std::stringstream text;
  text << in.rdbuf();
  std::string data = text.str();
  data.insert(data.find("Atoms # bond"), kHybridCoeffs);
  const std::string path = deli::testing::process_temp_dir() + "/deli_hybrid_bond_coeffs_" +
                           std::to_string(::getpid()) + ".data";
  std::ofstream(path, std::ios::binary) << data;
  return path;
}

// LAMMPS' potential energy of the file, its bond styles declared before read_data so that
// the rows' style names are read.
double lammps_energy(const std::string& data, std::size_t atoms) {
  const char* args[] = {"deli", "-screen", "none", "-log", "none", "-nocite"};
  deli::prefer_single_process_mpi();
  void* lmp = lammps_open_no_mpi(6, const_cast<char**>(args), nullptr);
  for (const std::string& line : std::vector<std::string>{
           "units lj", "atom_style bond", "bond_style hybrid fene harmonic", "read_data " + data,
           "pair_style lj/cut 1.122462048309373", "pair_modify shift yes", "pair_coeff 1 1 1.0 1.0",
           "special_bonds lj 0.0 1.0 1.0", "run 0"}) {
    lammps_command(lmp, line.c_str());
  }
  const double pe = lammps_get_thermo(lmp, "pe") * static_cast<double>(atoms);
  lammps_close(lmp);
  return pe;
}

TEST(HybridDataCoefficients, RunWithTheStylesTheyName) {
  const RunInput reference = load_run_input(kSource + "/tests/crosscheck/inputs/mixed_bonds.toml");
  const double expected = testing::evaluate(reference).evaluation.potential;

  const std::string data = write_hybrid_data();
  const RunInput from_file = testing::input_from(
      "[system]\ndata = \"" + data +
      "\"\n[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n[forcefield.pair]\nstyle = \"wca\"\n"
      "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]\n[forcefield.bond]\n"
      "style = \"fene\"\n[integrator]\ntimestep = 0.005\n[run]\nsteps = 0\n");
  const BondedSpec& bonds = *from_file.force_field_spec.bond;
  ASSERT_EQ(bonds.style_by_type.size(), 2u);
  EXPECT_EQ(bonds.style_by_type[0]->name, "fene");
  EXPECT_EQ(bonds.style_by_type[1]->name, "harmonic");
  EXPECT_EQ(bonds.by_type[1], (std::vector<double>{100.0, 0.97}));
  const double deli = testing::evaluate(from_file).evaluation.potential;
  const double lammps = lammps_energy(data, from_file.system.particles.size());
  std::printf(
      "hybrid bonds: deli with TOML coefficients %.15g, from the file %.15g, LAMMPS %.15g\n",
      expected, deli, lammps);
  // The same numbers, summed in the same order: the same energy bit for bit.
  EXPECT_EQ(deli, expected);
  EXPECT_NEAR(deli, lammps, 1e-12 * std::abs(lammps));
  std::remove(data.c_str());
}

}  // namespace
}  // namespace deli
