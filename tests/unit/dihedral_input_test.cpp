// Dihedrals in the inputs: the data file's Dihedrals and Dihedral Coeffs sections (as
// LAMMPS write_data writes them), deli's write-data, [forcefield.dihedral], and the
// refusals of each, every one naming its file, line or key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "input/lammps_data.hpp"
#include "support/scratch_files.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// Five atoms in a zigzag, two dihedrals of two types (1-2-3-4 and 2-3-4-5).
const std::string kData = R"(five atoms, two dihedrals

5 atoms
4 bonds
2 dihedrals
1 atom types
1 bond types
2 dihedral types
0 10 xlo xhi
0 10 ylo yhi
0 10 zlo zhi

Masses

1 1.0

Dihedral Coeffs # harmonic

1 1.5 -1 3
2 0.7 1 1

Atoms # molecular

1 1 1 1.0 1.0 1.0
2 1 1 2.0 1.2 1.1
3 1 1 2.9 1.0 1.7
4 1 1 3.8 1.6 1.5
5 1 1 4.1 2.4 2.2

Bonds

1 1 1 2
2 1 2 3
3 1 3 4
4 1 4 5

Dihedrals

1 1 1 2 3 4
2 2 2 3 4 5
)";

std::string toml_for(const std::string& data, const std::string& dihedral_table) {
  return "[system]\ndata = \"" + data +
         "\"\nboundary = \"fff\"\n[forcefield.pair]\nstyle = \"none\"\n[forcefield.bond]\n"
         "style = \"harmonic\"\ncoeffs = [{type = 1, k = 50.0, r0 = 1.0}]\n" +
         dihedral_table + "[integrator]\ntimestep = 0.005\n[run]\nsteps = 0\n";
}
const std::string kTable = "[forcefield.dihedral]\nstyle = \"harmonic\"\n";

class DihedralInput : public ::testing::Test {
 protected:
  std::string write_file(const std::string& contents) { return files_.write(contents); }
  static std::string error_of(const std::string& toml) {
    try {
      testing::input_from(toml);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }
  static std::string data_error_of(const std::string& path) {
    try {
      read_lammps_data(path, {});
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }
  testing::ScratchFiles files_{"deli_DihedralInput_", ".data"};
};

TEST_F(DihedralInput, DataFileSectionsAreRead) {
  const LammpsDataFile file = read_lammps_data(write_file(kData), {});
  const Topology& t = file.system.topology;
  EXPECT_EQ(t.dihedral_types, 2);
  ASSERT_EQ(t.dihedrals.size(), 2u);
  EXPECT_EQ((std::array{t.dihedrals[1].i, t.dihedrals[1].j, t.dihedrals[1].k, t.dihedrals[1].l}),
            (std::array<std::int32_t, 4>{1, 2, 3, 4}));
  EXPECT_EQ(t.dihedrals[1].type, 1);
  EXPECT_EQ(file.dihedral.style, "harmonic");
  ASSERT_EQ(file.dihedral.rows.size(), 2u);
  EXPECT_EQ(file.dihedral.rows[0].values, (std::vector<double>{1.5, -1.0, 3.0}));
}

// The data file's coefficients are the model: the same energy as with every coefficient in
// the input, and the input's win where it gives them.
TEST_F(DihedralInput, DataCoefficientsAreTheModelAndTheInputsWin) {
  const std::string data = write_file(kData);
  const RunInput from_data = testing::input_from(toml_for(data, kTable));
  const RunInput from_input =
      testing::input_from(toml_for(data, kTable + "coeffs = [{type = 1, k = 1.5, d = -1, n = 3}, "
                                                  "{type = 2, k = 0.7, d = 1, n = 1}]\n"));
  const double e = testing::evaluate(from_data).evaluation.potential;
  EXPECT_EQ(e, testing::evaluate(from_input).evaluation.potential);
  ASSERT_EQ(from_data.notes.size(), 1u);
  EXPECT_THAT(from_data.notes[0], HasSubstr("dihedral coefficients: 2 types from " + data));
  const RunInput overridden = testing::input_from(
      toml_for(data, kTable + "coeffs = [{type = 2, k = 0.7, d = -1, n = 1}]\n"));
  EXPECT_NE(testing::evaluate(overridden).evaluation.potential, e);
}

TEST_F(DihedralInput, WriteDataRoundTrips) {
  const LammpsDataFile file = read_lammps_data(write_file(kData), {});
  const std::string written = write_file("");
  write_lammps_data(file.system, written, "molecular", "round trip");
  const LammpsDataFile back = read_lammps_data(written, {});
  ASSERT_EQ(back.system.topology.dihedrals.size(), 2u);
  EXPECT_EQ(back.system.topology.dihedral_types, 2);
  for (std::size_t d = 0; d < 2; ++d) {
    const Dihedral& a = file.system.topology.dihedrals[d];
    const Dihedral& b = back.system.topology.dihedrals[d];
    EXPECT_EQ((std::array{a.i, a.j, a.k, a.l, a.type}), (std::array{b.i, b.j, b.k, b.l, b.type}));
  }
  EXPECT_THAT(
      [&] {
        try {
          write_lammps_data(file.system, written, "angle", "t");
        } catch (const InputError& e) {
          return std::string(e.what());
        }
        return std::string("(no error)");
      }(),
      HasSubstr("dihedrals, which atom style 'angle' cannot hold"));
}

TEST_F(DihedralInput, DataFileRefusals) {
  std::string text = kData;
  text.replace(text.find("Atoms # molecular"), 17, "Atoms # angle");
  const std::string angle_style = write_file(text);
  EXPECT_THAT(data_error_of(angle_style), AllOf(HasSubstr(angle_style + ":"),
                                                HasSubstr("atom style 'angle' has no dihedrals")));

  text = kData;
  text.replace(text.find("2 2 2 3 4 5"), 11, "2 2 2 3 4 2");
  const std::string repeated = write_file(text);
  EXPECT_THAT(data_error_of(repeated),
              AllOf(HasSubstr(repeated + ":40:"), HasSubstr("expected four different atoms")));

  text = kData;
  text.replace(text.find("2 2 2 3 4 5"), 11, "2 3 2 3 4 5");
  const std::string bad_type = write_file(text);
  EXPECT_THAT(data_error_of(bad_type),
              AllOf(HasSubstr(bad_type + ":40:"), HasSubstr("dihedral type 3 is outside 1..2")));

  text = kData;
  text.replace(text.find("1 1.5 -1 3"), 10, "1 1.5 0 3");
  const std::string bad_d = write_file(text);
  EXPECT_THAT(error_of(toml_for(bad_d, kTable)),
              AllOf(HasSubstr(bad_d + ":19:"), HasSubstr("d must be +1 or -1, found 0"),
                    HasSubstr("harmonic dihedral coefficients K d n")));

  text = kData;
  text.replace(text.find("2 0.7 1 1"), 9, "2 0.7 1");
  const std::string short_row = write_file(text);
  EXPECT_THAT(error_of(toml_for(short_row, kTable)),
              AllOf(HasSubstr(short_row + ":20:"), HasSubstr("found 2 numbers")));
}

TEST_F(DihedralInput, TomlRefusals) {
  const std::string data = write_file(kData);
  const auto with_coeffs = [&](const std::string& coeffs) {
    return toml_for(data,
                    kTable + "coeffs = [" + coeffs + ", {type = 2, k = 0.7, d = 1, n = 1}]\n");
  };
  EXPECT_THAT(error_of(with_coeffs("{type = 1, k = 1.5, d = 2, n = 3}")),
              AllOf(HasSubstr("'forcefield.dihedral.coeffs[1].d'"),
                    HasSubstr("must be +1 or -1, found 2")));
  EXPECT_THAT(error_of(with_coeffs("{type = 1, k = 1.5, d = 1, n = 1.5}")),
              AllOf(HasSubstr("'forcefield.dihedral.coeffs[1].n'"),
                    HasSubstr("must be a whole number, 0 or more, found 1.5")));
  EXPECT_THAT(error_of(with_coeffs("{type = 1, k = 1.5, d = 1, n = -2}")),
              HasSubstr("must be a whole number, 0 or more, found -2"));
  EXPECT_THAT(error_of(with_coeffs("{type = 3, k = 1.5, d = 1, n = 2}")),
              AllOf(HasSubstr("'forcefield.dihedral.coeffs[1].type': dihedral type 3"),
                    HasSubstr("does not exist: the system has 2 dihedral type(s)")));
  EXPECT_THAT(error_of(toml_for(data, "")),
              HasSubstr("the system has dihedrals but the input has no [forcefield.dihedral] "
                        "table; add one with style = \"harmonic\""));
  EXPECT_THAT(error_of(toml_for(data, "[forcefield.dihedral]\nstyle = \"charmm\"\n")),
              HasSubstr("unknown value \"charmm\""));
}

}  // namespace
}  // namespace deli
