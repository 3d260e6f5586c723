// atoms_usable, the branch-free check that a list build makes on its way through the atoms,
// against the two scans that name a blown-up atom: by their definitions (first_non_finite_atom:
// a NaN or infinite position or velocity; first_runaway_atom: more than 1e15 from the box, or
// more than 1e9 periods out along a periodic axis), a range is usable exactly when neither
// scan names an atom in it.
#include "system/finite_state.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace deli {
namespace {

Particles three_atoms() {
  Particles p;
  p.resize(3);
  for (std::size_t i = 0; i < 3; ++i) {
    p.position[i] = {1.0 + static_cast<double>(i), 2.0, 3.0};
    p.velocity[i] = {0.5, -0.5, 0.25};
    p.id[i] = static_cast<std::int64_t>(i) + 1;
  }
  return p;
}

TEST(FiniteState, UsableExactlyWhereNeitherScanNamesAnAtom) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double largest = std::numeric_limits<double>::max();
  // Period 10 along x and y, z open.
  const Box box({0, 0, 0}, {10, 10, 10}, {true, true, false});
  struct Case {
    const char* what;
    bool position;  // else the velocity
    int axis;
    double value;
    bool usable;
  };
  const std::vector<Case> cases = {
      {"position NaN", true, 0, nan, false},
      {"position +inf", true, 1, inf, false},
      {"position -inf on the open axis", true, 2, -inf, false},
      {"velocity NaN", false, 2, nan, false},
      {"velocity -inf", false, 0, -inf, false},
      {"largest finite velocity", false, 1, largest, true},
      {"2e15 from the box on the open axis", true, 2, 2e15, false},
      {"1e14 out along the open axis", true, 2, 1e14, true},
      {"2e10 periods out along x (2e11)", true, 0, 2e11, false},
      {"9e8 periods out along y (9e9)", true, 1, -9e9, true},
  };
  for (const Case& c : cases) {
    Particles p = three_atoms();
    (c.position ? p.position : p.velocity)[1][c.axis] = c.value;
    const bool named = first_non_finite_atom(p) || first_runaway_atom(p, box);
    EXPECT_EQ(named, !c.usable) << c.what;
    EXPECT_EQ(atoms_usable(p, box, 0, 3), c.usable) << c.what;
    // The atom is the second: ranges without it are usable.
    EXPECT_TRUE(atoms_usable(p, box, 0, 1)) << c.what;
    EXPECT_TRUE(atoms_usable(p, box, 2, 3)) << c.what;
    EXPECT_EQ(atoms_usable(p, box, 1, 2), c.usable) << c.what;
  }
  EXPECT_TRUE(atoms_usable(three_atoms(), box, 0, 3));
  EXPECT_TRUE(atoms_usable(three_atoms(), box, 0, 0));
}

}  // namespace
}  // namespace deli
