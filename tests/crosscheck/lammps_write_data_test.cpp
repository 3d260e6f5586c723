// Data files written by LAMMPS itself (write_data, with its coefficient sections) run in
// deli with the coefficients they carry, as read_data takes them: the reference is the
// same model with every coefficient in the TOML, and LAMMPS' own energy of the file.
#include <gtest/gtest.h>
#include <library.h>

#include <cmath>
#include <fstream>

#include "crosscheck/single_process_mpi.hpp"
#include "input/lammps_data.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"
#include "support/source_tree.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

using testing::kSource;

// The Kremer-Grest melt (FENE + WCA, special_bonds fene) handed to LAMMPS, which writes it
// back with `write_data FILE [pair ij]`; returns LAMMPS' potential energy.
double lammps_write_data(const System& system, const std::string& out, bool pair_ij) {
  // ctest runs the cases in parallel: one file per case.
  const std::string in = out + ".deli_for_lammps";
  write_lammps_data(system, in, "bond", "deli melt for LAMMPS");
  const char* args[] = {"deli", "-screen", "none", "-log", "none", "-nocite"};
  deli::prefer_single_process_mpi();
  void* lmp = lammps_open_no_mpi(6, const_cast<char**>(args), nullptr);
  for (const std::string& line : std::vector<std::string>{
           "units lj", "atom_style bond", "read_data " + in, "pair_style lj/cut 1.122462048309373",
           "pair_modify shift yes", "pair_coeff 1 1 1.0 1.0", "bond_style fene",
           "bond_coeff 1 30.0 1.5 1.0 1.0", "special_bonds fene", "run 0"}) {
    lammps_command(lmp, line.c_str());
  }
  // Read before write_data, after which the thermo computes are no longer current.
  const double pe = lammps_get_thermo(lmp, "pe") * static_cast<double>(system.particles.size());
  lammps_command(lmp, ("write_data " + out + (pair_ij ? " pair ij" : "")).c_str());
  lammps_close(lmp);
  return pe;
}

std::string input_for(const std::string& data, const std::string& bond_coeffs) {
  return "[system]\ndata = \"" + data +
         "\"\n[forcefield.special_bonds]\nlj = [0.0, 1.0, 1.0]\n[forcefield.pair]\n"
         "style = \"lj/cut\"\ncutoff = 1.122462048309373\nshift = true\n"
         "[forcefield.bond]\nstyle = \"fene\"\n" +
         bond_coeffs + "[integrator]\ntimestep = 0.005\n[run]\nsteps = 0\n";
}

class LammpsWrittenData : public ::testing::TestWithParam<bool> {};

TEST_P(LammpsWrittenData, RunsWithItsCoefficients) {
  const RunInput reference = load_run_input(kSource + "/inputs/lj_chains/melt.toml");
  const double deli_reference = testing::evaluate(reference).evaluation.potential;
  const std::string data = deli::testing::process_temp_dir() + "/written_by_lammps_" +
                           (GetParam() ? "pair_ij" : "pair") + ".data";
  const double lammps = lammps_write_data(reference.system, data, GetParam());
  {
    std::ifstream file(data);
    const std::string text((std::istreambuf_iterator<char>(file)), {});
    ASSERT_NE(text.find(GetParam() ? "PairIJ Coeffs # lj/cut" : "Pair Coeffs # lj/cut"),
              std::string::npos);
    ASSERT_NE(text.find("Bond Coeffs # fene"), std::string::npos);
  }
  const RunInput from_file = testing::input_from(input_for(data, ""));
  const double deli = testing::evaluate(from_file).evaluation.potential;
  if (GetParam()) {
    // PairIJ carries the cutoff, which LAMMPS writes with %g (1.12246) and read_data takes
    // over the global one: the reference is the model with that cutoff.
    std::string explicit_cutoff = input_for(data,
                                            "coeffs = [{ type = 1, k = 30.0, r0 = 1.5, "
                                            "epsilon = 1.0, sigma = 1.0 }]\n");
    explicit_cutoff.replace(explicit_cutoff.find("shift = true\n"), 13,
                            "shift = true\ncoeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0, "
                            "cutoff = 1.12246 }]\n");
    const double with_written_cutoff =
        testing::evaluate(testing::input_from(explicit_cutoff)).evaluation.potential;
    EXPECT_NEAR(deli, with_written_cutoff, 1e-12 * std::abs(deli_reference));
    EXPECT_GT(std::abs(deli - deli_reference), 1e-12 * std::abs(deli_reference));
    return;
  }
  std::printf(
      "melt: deli with TOML coefficients %.12g, deli from LAMMPS' file %.12g, LAMMPS %.12g\n",
      deli_reference, deli, lammps);
  EXPECT_NEAR(deli, deli_reference, 1e-12 * std::abs(deli_reference));
  EXPECT_NEAR(deli, lammps, 1e-10 * std::abs(lammps));
  ASSERT_EQ(from_file.notes.size(), 2u);
  EXPECT_NE(from_file.notes[0].find("pair coefficients: 1 entry from " + data), std::string::npos)
      << from_file.notes[0];
  EXPECT_NE(from_file.notes[1].find("bond coefficients: 1 type from " + data), std::string::npos)
      << from_file.notes[1];

  // The input's coefficients win where it gives them: a stiffer FENE spring.
  const RunInput stiffer = testing::input_from(
      input_for(data, "coeffs = [{ type = 1, k = 40.0, r0 = 1.5, epsilon = 1.0, sigma = 1.0 }]\n"));
  RunInput reference_stiffer = load_run_input(kSource + "/inputs/lj_chains/melt.toml");
  reference_stiffer.force_field_spec.bond->by_type[0][0] = 40.0;  // FENE K
  reference_stiffer.force_field =
      build_force_field(reference_stiffer.force_field_spec, reference_stiffer.system);
  EXPECT_NEAR(testing::evaluate(stiffer).evaluation.potential,
              testing::evaluate(reference_stiffer).evaluation.potential,
              1e-12 * std::abs(deli_reference));
  EXPECT_NE(stiffer.notes[1].find("1 type from the input (the input's win)"), std::string::npos)
      << stiffer.notes[1];
}

INSTANTIATE_TEST_SUITE_P(PairAndPairIJ, LammpsWrittenData, ::testing::Values(false, true));

// Coefficients of another style than the input names are refused, naming the section.
TEST(LammpsWrittenDataStyles, CoefficientsOfAnotherStyleAreRefused) {
  const RunInput reference = load_run_input(kSource + "/inputs/lj_chains/melt.toml");
  const std::string data = deli::testing::process_temp_dir() + "/written_by_lammps_fene.data";
  lammps_write_data(reference.system, data, false);
  std::string text = input_for(data, "");
  text.replace(text.find("style = \"fene\""), 14, "style = \"harmonic\"");
  try {
    testing::input_from(text);
    FAIL() << "harmonic bonds took FENE coefficients";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Bond Coeffs are for style 'fene'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace deli
