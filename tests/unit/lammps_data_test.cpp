#include "input/lammps_data.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace deli {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

class LammpsDataTest : public ::testing::Test {
 protected:
  void TearDown() override {
    for (const std::string& path : paths_) std::filesystem::remove(path);
  }

  // A fresh path per call, so that tests running in parallel processes never share files.
  std::string temp_path() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("deli_") + info->test_suite_name() + "_" + info->name() + "_" +
                       std::to_string(::getpid()) + "_" + std::to_string(paths_.size()) + ".data";
    for (char& c : name) {
      if (c == '/') c = '_';
    }
    paths_.push_back((std::filesystem::temp_directory_path() / name).string());
    return paths_.back();
  }

  std::string write_file(const std::string& contents) {
    const std::string path = temp_path();
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }

  // The message of the InputError that reading `path` raises; fails the test if none.
  static std::string read_error(const std::string& path, const LammpsDataOptions& options = {}) {
    try {
      read_lammps_data(path, options);
    } catch (const InputError& e) {
      return e.what();
    }
    ADD_FAILURE() << "reading " << path << " did not throw InputError";
    return "";
  }

  static void expect_error_at(const std::string& message, const std::string& path, long line,
                              std::initializer_list<const char*> words) {
    EXPECT_THAT(message, StartsWith(path + ":" + std::to_string(line) + ": "));
    for (const char* word : words) EXPECT_THAT(message, HasSubstr(word));
  }

 private:
  std::vector<std::string> paths_;
};

System make_system() {
  System s;
  s.box = Box({-1.5, 0.0, 2.25}, {10.1, 7.3, 12.7}, {true, false, true});
  s.atom_types = {{1.0 / 3.0, 0.5}, {2.5, 0.5}};
  Particles& p = s.particles;
  p.resize(5);
  p.id = {3, 7, 10, 42, 1000};
  p.molecule = {1, 1, 1, 2, 0};
  p.type = {0, 1, 0, 1, 0};
  p.position = {{0.1 + 0.2, 1.0 / 7.0, 2.25},
                {std::nextafter(10.1, 0.0), -3.7, 5.0},  // y is open: outside the bounds is fine
                {-1.5, 100.125, std::nextafter(12.7, 0.0)},
                {4.4, 0.0, 3.0 + 1e-15},
                {9.99999999999, 7.3, 11.0}};
  p.image = {{0, 0, 0}, {-1, 2, 3}, {5, -7, 0}, {0, 0, -2}, {1, 1, 1}};
  p.velocity = {
      {1e-300, -2.5e17, 0.0}, {-0.0, 1.0 / 3.0, 7.0}, {0.5, 0.25, -0.125}, {}, {3.0, -2.0, 1.0}};
  for (std::size_t i = 0; i < p.size(); ++i) p.mass[i] = s.atom_types[p.type[i]].mass;
  s.topology.bond_types = 2;
  s.topology.angle_types = 1;
  s.topology.bonds = {{0, 1, 0}, {1, 2, 1}, {3, 4, 0}};
  s.topology.angles = {{0, 1, 2, 0}};
  return s;
}

// Bit-for-bit comparison: EXPECT_EQ on doubles, but -0.0 and 0.0 must also stay apart.
void expect_same_bits(const Vec3& a, const Vec3& b) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(a[k], b[k]);
    EXPECT_EQ(std::signbit(a[k]), std::signbit(b[k]));
  }
}

void expect_same_system(const System& expected, const System& actual, bool with_molecules) {
  const Particles& e = expected.particles;
  const Particles& a = actual.particles;
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(actual.box.lo()[k], expected.box.lo()[k]);
    EXPECT_EQ(actual.box.hi()[k], expected.box.hi()[k]);
    EXPECT_EQ(actual.box.periodic(k), expected.box.periodic(k));
  }
  ASSERT_EQ(actual.atom_types.size(), expected.atom_types.size());
  for (std::size_t t = 0; t < expected.atom_types.size(); ++t) {
    EXPECT_EQ(actual.atom_types[t].mass, expected.atom_types[t].mass);
  }
  ASSERT_EQ(a.size(), e.size());
  for (std::size_t i = 0; i < e.size(); ++i) {
    SCOPED_TRACE("particle " + std::to_string(i));
    EXPECT_EQ(a.id[i], e.id[i]);
    EXPECT_EQ(a.type[i], e.type[i]);
    EXPECT_EQ(a.molecule[i], with_molecules ? e.molecule[i] : 0);
    EXPECT_EQ(a.mass[i], e.mass[i]);
    EXPECT_EQ(a.radius[i], 0.5);
    EXPECT_EQ(a.image[i], e.image[i]);
    expect_same_bits(a.position[i], e.position[i]);
    expect_same_bits(a.velocity[i], e.velocity[i]);
  }
}

TEST_F(LammpsDataTest, RoundTripIsBitExactForEveryMolecularStyle) {
  const System system = make_system();
  for (const char* style : {"angle", "molecular", "full"}) {
    SCOPED_TRACE(style);
    const std::string path = temp_path();
    write_lammps_data(system, path, style, "round trip test");
    const LammpsDataFile file = read_lammps_data(path, {{true, false, true}, ""});
    EXPECT_EQ(file.atom_style, style);
    EXPECT_TRUE(file.has_velocities);
    expect_same_system(system, file.system, true);

    const Topology& t = file.system.topology;
    EXPECT_EQ(t.bond_types, 2);
    EXPECT_EQ(t.angle_types, 1);
    ASSERT_EQ(t.bonds.size(), system.topology.bonds.size());
    for (std::size_t b = 0; b < t.bonds.size(); ++b) {
      EXPECT_EQ(t.bonds[b].i, system.topology.bonds[b].i);
      EXPECT_EQ(t.bonds[b].j, system.topology.bonds[b].j);
      EXPECT_EQ(t.bonds[b].type, system.topology.bonds[b].type);
    }
    ASSERT_EQ(t.angles.size(), 1u);
    EXPECT_EQ(t.angles[0].i, 0);
    EXPECT_EQ(t.angles[0].j, 1);
    EXPECT_EQ(t.angles[0].k, 2);
    EXPECT_EQ(t.angles[0].type, 0);
  }
}

TEST_F(LammpsDataTest, RoundTripAtomicStyle) {
  System system = make_system();
  system.topology = Topology{};
  const std::string path = temp_path();
  write_lammps_data(system, path, "atomic", "atomic");
  const LammpsDataFile file = read_lammps_data(path, {{true, false, true}, ""});
  EXPECT_EQ(file.atom_style, "atomic");
  expect_same_system(system, file.system, false);
  EXPECT_TRUE(file.system.topology.bonds.empty());
}

TEST_F(LammpsDataTest, WriterWrapsAtomsOutsideThePeriodicBox) {
  System system = make_system();
  system.particles.position[3] = {12.0, 1.0, 1.0};  // past xhi and below zlo
  const std::string path = temp_path();
  write_lammps_data(system, path, "molecular", "wrapped");
  const System read = read_lammps_data(path, {{true, false, true}, ""}).system;
  const Vec3 expected =
      system.box.unwrapped(system.particles.position[3], system.particles.image[3]);
  const Vec3 actual = read.box.unwrapped(read.particles.position[3], read.particles.image[3]);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(actual[k], expected[k], 1e-12);
  EXPECT_EQ(read.particles.image[3], (std::array<int, 3>{1, 0, -3}));
}

TEST_F(LammpsDataTest, WriterRejectsBondsInAtomicStyle) {
  const std::string path = temp_path();
  try {
    write_lammps_data(make_system(), path, "atomic", "t");
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bonds"));
  }
}

TEST_F(LammpsDataTest, ReadsAtomicStyleInferredFromFiveColumns) {
  const std::string path = write_file(R"(title
3 atoms
2 atom types
0 dihedrals
0 extra bond per atom
0 10 xlo xhi
0 10 ylo yhi
-5 5 zlo zhi

Masses

1 1.5
2 2.0  # comment

Atoms

9 2 1.0 2.0 3.0
2 1 4.0 5.0 -4.5
5 1 0 0 0
)");
  const LammpsDataFile file = read_lammps_data(path, {});
  EXPECT_EQ(file.atom_style, "atomic");
  EXPECT_FALSE(file.has_velocities);
  const Particles& p = file.system.particles;
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p.id, (std::vector<std::int64_t>{2, 5, 9}));
  EXPECT_EQ(p.type, (std::vector<int>{0, 0, 1}));
  EXPECT_EQ(p.mass, (std::vector<double>{1.5, 1.5, 2.0}));
  EXPECT_EQ(p.molecule, (std::vector<std::int64_t>{0, 0, 0}));
  EXPECT_EQ(p.position[2].x, 1.0);
  EXPECT_EQ(p.position[0].z, -4.5);
  EXPECT_EQ(p.velocity[1].x, 0.0);
  EXPECT_EQ(file.system.box.lo().z, -5.0);
  EXPECT_EQ(file.system.atom_types.size(), 2u);
}

TEST_F(LammpsDataTest, ReadsAtomicStyleWithImagesAndVelocities) {
  const std::string path = write_file(R"(title

2 atoms
1 atom types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1

Atoms # atomic

1 1 1 1 1 -1 0 2
2 1 2 2 2 0 3 0

Velocities

2 0.5 0.25 0.125
1 -1 -2 -3
)");
  const LammpsDataFile file = read_lammps_data(path, {});
  EXPECT_EQ(file.atom_style, "atomic");
  EXPECT_TRUE(file.has_velocities);
  const Particles& p = file.system.particles;
  EXPECT_EQ(p.image[0], (std::array<int, 3>{-1, 0, 2}));
  EXPECT_EQ(p.image[1], (std::array<int, 3>{0, 3, 0}));
  EXPECT_EQ(p.velocity[0].z, -3.0);
  EXPECT_EQ(p.velocity[1].x, 0.5);
}

TEST_F(LammpsDataTest, ReadsBondStyleFromHint) {
  const std::string path = write_file(R"(title
3 atoms
2 bonds
1 atom types
1 bond types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1

Atoms # bond

30 4 1 1 1 1
10 4 1 2 2 2
20 4 1 3 3 3

Bonds

1 1 10 20
2 1 20 30
)");
  const LammpsDataFile file = read_lammps_data(path, {});
  EXPECT_EQ(file.atom_style, "bond");
  const System& s = file.system;
  EXPECT_EQ(s.particles.molecule, (std::vector<std::int64_t>{4, 4, 4}));
  EXPECT_EQ(s.topology.bond_types, 1);
  ASSERT_EQ(s.topology.bonds.size(), 2u);
  EXPECT_EQ(s.topology.bonds[0].i, 0);
  EXPECT_EQ(s.topology.bonds[0].j, 1);
  EXPECT_EQ(s.topology.bonds[1].i, 1);
  EXPECT_EQ(s.topology.bonds[1].j, 2);
  EXPECT_EQ(s.topology.bonds[1].type, 0);
}

TEST_F(LammpsDataTest, ReadsAngleStyleFromOption) {
  const std::string path = write_file(R"(title
3 atoms
2 bonds
1 angles
2 atom types
1 bond types
2 angle types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1
2 3

Atoms

1 1 2 1 1 1 0 0 0
2 1 1 2 2 2 0 0 0
3 1 2 3 3 3 0 0 0

Bonds

1 1 1 2
2 1 2 3

Angles

1 2 1 2 3
)");
  const LammpsDataFile file = read_lammps_data(path, {{true, true, true}, "angle"});
  EXPECT_EQ(file.atom_style, "angle");
  const Topology& t = file.system.topology;
  EXPECT_EQ(t.angle_types, 2);
  ASSERT_EQ(t.angles.size(), 1u);
  EXPECT_EQ(t.angles[0].j, 1);
  EXPECT_EQ(t.angles[0].type, 1);
  EXPECT_EQ(file.system.particles.mass, (std::vector<double>{3, 1, 3}));
}

TEST_F(LammpsDataTest, ReadsMolecularStyleInferredFromNineColumns) {
  const std::string path = write_file(
      "title\r\n2 atoms\r\n1 atom types\r\n0 5 xlo xhi\r\n0 5 ylo yhi\r\n0 5 zlo zhi\r\n\r\n"
      "Masses\r\n\r\n1 1\r\n\r\nAtoms\r\n\r\n1 7 1 1 1 1 0 0 1\r\n2 8 1 2 2 2 0 0 -1\r\n");
  const LammpsDataFile file = read_lammps_data(path, {});
  EXPECT_EQ(file.atom_style, "molecular");
  EXPECT_EQ(file.system.particles.molecule, (std::vector<std::int64_t>{7, 8}));
  EXPECT_EQ(file.system.particles.image[1], (std::array<int, 3>{0, 0, -1}));
}

TEST_F(LammpsDataTest, ReadsFullStyleWithZeroCharges) {
  for (const char* atoms :
       {"1 1 1 0.0 1 1 1\n2 1 1 -0 2 2 2\n", "1 1 1 0.0 1 1 1 0 0 0\n2 1 1 -0 2 2 2 1 1 1\n"}) {
    const std::string path = write_file(std::string(R"(title
2 atoms
1 atom types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1

Atoms

)") + atoms);
    const LammpsDataFile file = read_lammps_data(path, {});
    EXPECT_EQ(file.atom_style, "full");
    EXPECT_EQ(file.system.particles.position[1].x, 2.0);
  }
}

TEST_F(LammpsDataTest, OpenAxesAcceptAtomsOutsideTheBounds) {
  const std::string path = write_file(R"(title
1 atoms
1 atom types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1

Atoms

1 1 1 -2 7
)");
  const LammpsDataFile wrapped = read_lammps_data(path, {{true, true, true}, ""});
  EXPECT_EQ(wrapped.system.particles.position[0].y, 3.0);
  EXPECT_EQ(wrapped.system.particles.image[0][1], -1);
  EXPECT_EQ(wrapped.system.particles.position[0].z, 2.0);
  EXPECT_EQ(wrapped.system.particles.image[0][2], 1);
  const LammpsDataFile file = read_lammps_data(path, {{true, false, false}, ""});
  EXPECT_EQ(file.system.particles.position[0].z, 7.0);
}

// Files built on this preamble have their section header on line 12, first data line on 14.
constexpr const char* kPreamble = R"(title
3 atoms
1 atom types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1
)";

// Coefficient sections as LAMMPS write_data writes them are read as written (the force
// field reader gives them meaning); improper coefficients have no model here.
TEST_F(LammpsDataTest, PairCoefficientsAreRead) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Pair Coeffs # lj/cut

1 1.0 1.1

Atoms # atomic

1 1 1 1 1
2 1 2 2 2
3 1 3 3 3
)");
  const LammpsDataFile file = read_lammps_data(path, {});
  EXPECT_EQ(file.pair.style, "lj/cut");
  EXPECT_EQ(file.pair.line, 12);
  ASSERT_EQ(file.pair.rows.size(), 1u);
  EXPECT_EQ(file.pair.rows[0].types, std::vector<int>{0});
  EXPECT_EQ(file.pair.rows[0].values, (std::vector<double>{1.0, 1.1}));
}

TEST_F(LammpsDataTest, CoefficientsOfATypeOutsideTheHeaderAreAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Pair Coeffs # lj/cut

2 1.0 1.0
)");
  expect_error_at(read_error(path), path, 14, {"atom type 2", "outside"});
}

TEST_F(LammpsDataTest, ImproperCoefficientSectionIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Improper Coeffs # harmonic

1 1.0 2.0
)");
  expect_error_at(read_error(path), path, 12, {"Improper Coeffs", "remove this section"});
}

TEST_F(LammpsDataTest, BondNamingUnknownAtomIsAnError) {
  const std::string path = write_file(R"(title
2 atoms
1 bonds
1 atom types
1 bond types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1

Atoms # molecular

1 1 1 1 1 1
2 1 1 2 2 2

Bonds

1 1 1 99
)");
  expect_error_at(read_error(path), path, 21, {"Bonds", "atom id 99", "not in the Atoms section"});
}

TEST_F(LammpsDataTest, WrongColumnCountIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms # full

1 1 1 0 1 1 1
2 1 1 1 1 1
3 1 1 0 2 2 2
)");
  expect_error_at(read_error(path), path, 15, {"6 columns", "'full'", "expects 7", "or 10"});
}

TEST_F(LammpsDataTest, InferenceFailureNamesTheColumnCount) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms

1 1 1 1
)");
  expect_error_at(read_error(path), path, 14, {"4 columns", "atomic", "molecular", "full"});
}

TEST_F(LammpsDataTest, CountMismatchIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms

1 1 1 1 1
2 1 2 2 2
)");
  expect_error_at(read_error(path), path, 12, {"Atoms section has 2 lines", "declares 3 atoms"});
}

TEST_F(LammpsDataTest, NonzeroChargeIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms # full

1 1 1 0 1 1 1
2 1 1 0.5 1 1 1
3 1 1 0 2 2 2
)");
  expect_error_at(read_error(path), path, 15, {"atom 2", "charge 0.5", "electrostatics"});
}

TEST_F(LammpsDataTest, TriclinicBoxIsAnError) {
  const std::string path = write_file(R"(title
1 atoms
1 atom types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi
0.0 0.0 0.0 xy xz yz
)");
  expect_error_at(read_error(path), path, 7, {"xy xz yz", "triclinic", "orthorhombic"});
}

TEST_F(LammpsDataTest, AtomOutsidePeriodicBoxIsWrappedAsLammpsDoes) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms

1 1 1 1 1
2 1 5 1 1 2 0 0
3 1 2 2 2
)");
  const LammpsDataFile file = read_lammps_data(path, {});
  EXPECT_EQ(file.system.particles.position[1].x, 0.0);
  EXPECT_EQ(file.system.particles.image[1][0], 3);
}

TEST_F(LammpsDataTest, HintAndOptionMismatchIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms # full

1 1 1 0 1 1 1
2 1 1 0 1 1 1
3 1 1 0 2 2 2
)");
  expect_error_at(read_error(path, {{true, true, true}, "molecular"}), path, 12,
                  {"'# full'", "'molecular'"});
}

TEST_F(LammpsDataTest, UnsupportedHeaderCountIsAnError) {
  const std::string path = write_file("title\n1 atoms\n2 impropers\n");
  expect_error_at(read_error(path), path, 3, {"2 impropers", "does not support"});
}

TEST_F(LammpsDataTest, MalformedNumberIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms

1 1 1 1 1
2 1 1.2.3 1 1
3 1 2 2 2
)");
  expect_error_at(read_error(path), path, 15, {"x of atom 2", "'1.2.3'"});
}

TEST_F(LammpsDataTest, DuplicateAtomIdIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms

1 1 1 1 1
2 1 1 1 1
1 1 2 2 2
)");
  expect_error_at(read_error(path), path, 16, {"atom id 1", "twice", "line 14"});
}

TEST_F(LammpsDataTest, TypeOutOfRangeIsAnError) {
  const std::string path = write_file(std::string(kPreamble) + R"(
Atoms

1 1 1 1 1
2 2 1 1 1
3 1 2 2 2
)");
  expect_error_at(read_error(path), path, 15, {"atom type 2", "1..1"});
}

TEST_F(LammpsDataTest, MissingMassIsAnError) {
  const std::string path = write_file(R"(title
1 atoms
2 atom types
0 5 xlo xhi
0 5 ylo yhi
0 5 zlo zhi

Masses

1 1

Atoms

1 2 1 1 1
)");
  expect_error_at(read_error(path), path, 14, {"atom 1", "type 2", "Masses"});
}

TEST_F(LammpsDataTest, MissingFileIsAnError) {
  const std::string path = temp_path();
  EXPECT_THAT(read_error(path), HasSubstr(path));
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// Found by fuzzing (tools/fuzz.sh lammps_data): an atom 4e16 box lengths outside a periodic
// box made the wrap cast its crossing count to int (undefined). Refused, with its line;
// one a few boxes away is still mapped back, as LAMMPS does.
TEST_F(LammpsDataTest, AtomTooFarOutsideAPeriodicBoxIsAnError) {
  const std::string head =
      "far atom\n\n2 atoms\n1 atom types\n\n-6 6 xlo xhi\n-6 6 ylo yhi\n-6 6 zlo zhi\n\n"
      "Masses\n\n1 1\n\nAtoms # atomic\n\n1 1 0.5 0 0\n";
  const std::string far = write_file(head + "2 1 43301270189221935 -0.25 0\n");
  expect_error_at(read_error(far), far, 17, {"x of atom 2", "43301270189221935", "32 bits"});
  const std::string near = write_file(head + "2 1 30.5 -0.25 0\n");
  const LammpsDataFile file = read_lammps_data(near, {});
  EXPECT_EQ(file.system.particles.image[1][0], 3);
  EXPECT_DOUBLE_EQ(file.system.particles.position[1].x, -5.5);
}

}  // namespace
}  // namespace deli
