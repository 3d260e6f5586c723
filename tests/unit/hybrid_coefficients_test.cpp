// Coefficient sections of LAMMPS' hybrid styles ("Bond Coeffs # hybrid", each row naming
// its style after its type, as read_data takes them): read as written, given to each type
// the style its row names, and refused with the file and line where they cannot be.
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

// Four atoms in a chain: bonds of types 1 and 2, angles of types 1 and 2.
std::string data_with(const std::string& coefficients) {
  return R"(hybrid coefficients

4 atoms
3 bonds
2 angles
1 atom types
2 bond types
2 angle types
0 10 xlo xhi
0 10 ylo yhi
0 10 zlo zhi

Masses

1 1.0

)" + coefficients +
         R"(
Atoms # angle

1 1 1 1.0 1.0 1.0
2 1 1 2.0 1.2 1.1
3 1 1 2.9 1.0 1.7
4 1 1 3.8 1.6 1.5

Bonds

1 1 1 2
2 2 2 3
3 1 3 4

Angles

1 1 1 2 3
2 2 2 3 4
)";
}

const std::string kBondCoeffs =
    "Bond Coeffs # hybrid\n\n1 fene 30.0 1.5 1.0 1.0\n2 harmonic 100.0 0.97\n\n";
const std::string kAngleCoeffs = "Angle Coeffs # hybrid\n\n1 harmonic 5.0 110.0\n2 cosine 1.5\n\n";

std::string toml_for(const std::string& data) {
  return "[system]\ndata = \"" + data +
         "\"\nboundary = \"fff\"\n[forcefield.pair]\nstyle = \"none\"\n[forcefield.bond]\n"
         "style = \"fene\"\n[forcefield.angle]\nstyle = \"harmonic\"\n[integrator]\n"
         "timestep = 0.005\n[run]\nsteps = 0\n";
}

class HybridCoefficients : public ::testing::Test {
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
  testing::ScratchFiles files_{"deli_HybridCoefficients_", ".data"};
};

TEST_F(HybridCoefficients, RowsKeepTheirStyle) {
  const LammpsDataFile file =
      read_lammps_data(write_file(data_with(kBondCoeffs + kAngleCoeffs)), {});
  EXPECT_EQ(file.bond.style, "hybrid");
  ASSERT_EQ(file.bond.rows.size(), 2u);
  EXPECT_EQ(file.bond.rows[0].style, "fene");
  EXPECT_EQ(file.bond.rows[0].values, (std::vector<double>{30.0, 1.5, 1.0, 1.0}));
  EXPECT_EQ(file.bond.rows[1].style, "harmonic");
  EXPECT_EQ(file.angle.rows[1].style, "cosine");
  EXPECT_EQ(file.angle.rows[1].values, std::vector<double>{1.5});
}

// Each type takes its row's style: the model equals the one with every coefficient (and
// the types' own styles) in the input.
TEST_F(HybridCoefficients, EachTypeTakesItsRowsStyle) {
  const RunInput from_data =
      testing::input_from(toml_for(write_file(data_with(kBondCoeffs + kAngleCoeffs))));
  EXPECT_EQ(from_data.force_field_spec.bond->style_by_type[1]->name, "harmonic");
  EXPECT_EQ(from_data.force_field_spec.angle->style_by_type[1]->name, "cosine");
  std::string toml = toml_for(write_file(data_with("")));
  toml.replace(toml.find("style = \"fene\"\n"), 15,
               "style = \"fene\"\ncoeffs = [{type = 1, k = 30.0, r0 = 1.5, epsilon = 1.0, "
               "sigma = 1.0}, {type = 2, style = \"harmonic\", k = 100.0, r0 = 0.97}]\n");
  toml.replace(toml.find("style = \"harmonic\"\n[integrator]"), 18,
               "style = \"harmonic\"\ncoeffs = [{type = 1, k = 5.0, theta0 = 110.0}, {type = 2, "
               "style = \"cosine\", k = 1.5}]\n");
  const RunInput from_input = testing::input_from(toml);
  const testing::Evaluated a = testing::evaluate(from_data), b = testing::evaluate(from_input);
  EXPECT_EQ(a.evaluation.potential, b.evaluation.potential);
  ASSERT_EQ(a.force.size(), b.force.size());
  for (std::size_t i = 0; i < a.force.size(); ++i) {
    EXPECT_TRUE(a.force[i].x == b.force[i].x && a.force[i].y == b.force[i].y &&
                a.force[i].z == b.force[i].z)
        << "atom " << i;
  }
}

TEST_F(HybridCoefficients, Refusals) {
  const std::string no_style =
      write_file(data_with("Bond Coeffs # hybrid\n\n1 fene 30.0 1.5 1.0 1.0\n2 100.0 0.97\n\n"));
  EXPECT_THAT(error_of(toml_for(no_style)),
              AllOf(HasSubstr(no_style + ":20:"), HasSubstr("marked '# hybrid'"),
                    HasSubstr("names no style")));
  const std::string unknown =
      write_file(data_with("Bond Coeffs # hybrid\n\n1 fene 30.0 1.5 1.0 1.0\n2 morse 1 2 1\n\n"));
  EXPECT_THAT(error_of(toml_for(unknown)),
              AllOf(HasSubstr(unknown + ":20:"), HasSubstr("bond style 'morse'"),
                    HasSubstr("\"harmonic\" or \"fene\"")));
  const std::string wrong_count = write_file(
      data_with("Bond Coeffs # hybrid\n\n1 fene 30.0 1.5 1.0 1.0\n2 harmonic 100.0\n\n"));
  EXPECT_THAT(error_of(toml_for(wrong_count)),
              AllOf(HasSubstr(wrong_count + ":20:"), HasSubstr("harmonic bond coefficients K r0"),
                    HasSubstr("found 1 numbers")));
  const std::string pair = write_file(data_with("Pair Coeffs # hybrid\n\n1 morse 1.0 2.0 1.0\n\n"));
  std::string toml = toml_for(pair);
  toml.replace(toml.find("style = \"none\"\n"), 15, "style = \"wca\"\n");
  EXPECT_THAT(error_of(toml), AllOf(HasSubstr(pair + ":19:"), HasSubstr("pair style 'morse'"),
                                    HasSubstr("one pair style per system")));
}

}  // namespace
}  // namespace deli
