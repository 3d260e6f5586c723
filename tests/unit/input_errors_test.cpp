// Bad input is refused with a message naming the file, the line and the key, what was
// found and what is expected.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "input/run_input.hpp"

namespace deli {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

const std::string kValid = R"([system]
[system.lattice]
type = "fcc"
density = 0.8442
cells = [3, 3, 3]

[forcefield.pair]
style = "lj/cut"
cutoff = 2.5
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]

[integrator]
timestep = 0.005

[run]
steps = 10
)";

std::string error_of(const std::string& text) {
  try {
    parse_run_input(text, "case.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(InputErrors, ValidInputLoads) {
  const RunInput input = parse_run_input(kValid, "case.toml");
  EXPECT_EQ(input.system.particles.size(), 108u);
  EXPECT_EQ(input.steps, 10);
}

TEST(InputErrors, UnknownKeySuggestsTheClosest) {
  EXPECT_THAT(
      error_of(replaced(kValid, "style", "styel")),
      AllOf(HasSubstr("case.toml:7:"), HasSubstr("missing required key 'forcefield.pair.style'"),
            HasSubstr("found 'styel'")));
  EXPECT_THAT(error_of(replaced(kValid, "[run]\n", "[run]\nstesp = 3\n")),
              AllOf(HasSubstr("case.toml:16:"), HasSubstr("unknown key 'run.stesp'"),
                    HasSubstr("did you mean 'steps'?")));
}

TEST(InputErrors, MissingRequiredKeyNamesIt) {
  EXPECT_THAT(
      error_of(replaced(kValid, "timestep = 0.005", "")),
      AllOf(HasSubstr("case.toml:12:"), HasSubstr("missing required key 'integrator.timestep'")));
}

TEST(InputErrors, WrongTypeSaysWhatWasFound) {
  EXPECT_THAT(error_of(replaced(kValid, "timestep = 0.005", "timestep = \"fast\"")),
              AllOf(HasSubstr("case.toml:13:"), HasSubstr("'integrator.timestep'"),
                    HasSubstr("expected a number, found a string")));
}

TEST(InputErrors, UnknownStyleSuggestsTheClosest) {
  EXPECT_THAT(error_of(replaced(kValid, "\"lj/cut\"", "\"lj/cutt\"")),
              AllOf(HasSubstr("case.toml:8:"), HasSubstr("unknown value \"lj/cutt\""),
                    HasSubstr("did you mean \"lj/cut\"?")));
}

TEST(InputErrors, NegativeTimestepRefused) {
  EXPECT_THAT(error_of(replaced(kValid, "timestep = 0.005", "timestep = -0.005")),
              AllOf(HasSubstr("case.toml:13:"), HasSubstr("must be a positive number")));
}

TEST(InputErrors, TomlSyntaxErrorHasItsLine) {
  EXPECT_THAT(error_of(replaced(kValid, "steps = 10", "steps = = 10")), HasSubstr("case.toml:16:"));
}

TEST(InputErrors, MissingLikePairCoefficients) {
  EXPECT_THAT(
      error_of(replaced(kValid, "coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]",
                        "coeffs = []")),
      AllOf(HasSubstr("no coefficients for atom type 1 with itself"), HasSubstr("case.toml:10:")));
}

TEST(InputErrors, PairTypeOutOfRange) {
  EXPECT_THAT(error_of(replaced(kValid, "types = [1, 1]", "types = [1, 2]")),
              AllOf(HasSubstr("atom type 2"), HasSubstr("has 1 atom type(s)")));
}

TEST(InputErrors, MissingDataFileNamed) {
  EXPECT_THAT(error_of(replaced(
                  kValid, "[system.lattice]\ntype = \"fcc\"\ndensity = 0.8442\ncells = [3, 3, 3]",
                  "data = \"no_such.data\"")),
              AllOf(HasSubstr("no_such.data does not exist"), HasSubstr("case.toml:2:")));
}

TEST(InputErrors, TwoSystemSourcesRefused) {
  EXPECT_THAT(error_of(replaced(kValid, "[system]\n", "[system]\ndata = \"x.data\"\n")),
              HasSubstr("give exactly one of 'data'"));
}

TEST(InputErrors, BoxSmallerThanTwiceTheCutoff) {
  EXPECT_THAT(error_of(replaced(kValid, "cells = [3, 3, 3]", "cells = [3, 3, 2]")),
              AllOf(HasSubstr("less than twice the pair cutoff"), HasSubstr("along z")));
}

TEST(InputErrors, BondsWithoutBondStyle) {
  const std::string chains =
      replaced(kValid, "[system.lattice]\ntype = \"fcc\"\ndensity = 0.8442\ncells = [3, 3, 3]",
               "[system.chains]\ncount = 4\nlength = 10\ndensity = 0.3\nseed = 3");
  EXPECT_THAT(error_of(chains), HasSubstr("no [forcefield.bond] table"));
}

TEST(InputErrors, BadBoundaryLetter) {
  EXPECT_THAT(error_of(replaced(kValid, "[system]\n", "[system]\nboundary = \"ppx\"\n")),
              AllOf(HasSubstr("case.toml:2:"), HasSubstr("letter 'x'")));
}

}  // namespace
}  // namespace deli
