// The external fields (gravity, inverse square, radial polynomial): forces are minus the
// gradient of their energy (central differences), and several fields in one input are
// reported as one "external" term, summed (as the cross-checks compare them).
#include <gtest/gtest.h>

#include <cmath>

#include "support/test_systems.hpp"

namespace deli {
namespace {

using testing::evaluate;
using testing::input_from;

// Random chains in an open box (fields act on positions as stored: open boxes), with every
// field at once, the centres off the chains so that s = |x - c|^2 stays away from 0.
std::string fields_input(const std::string& fields) {
  return "[system]\nboundary = \"fff\"\n[system.chains]\ncount = 4\nlength = 6\ndensity = 0.3\n"
         "bond_length = 0.97\nmin_distance = 0.85\nseed = 11\n[forcefield]\n"
         "[forcefield.pair]\nstyle = \"none\"\n[forcefield.bond]\nstyle = \"harmonic\"\n"
         "coeffs = [{type = 1, k = 100.0, r0 = 1.0}]\n[forcefield.external]\n" +
         fields + "[integrator]\ntimestep = 0.005\n[run]\nsteps = 0\n";
}

const std::string kAllFields =
    "gravity = [0.3, -0.2, -9.8]\n"
    "inverse_square = { strength = 2.5, center = [-20.0, -20.0, -20.0] }\n"
    "radial_polynomial = { degree = 3, coefficients = [0.5, 0.01, -2e-4, 1e-6], "
    "center = [1.0, 2.0, 3.0] }\n";

// Central differences, h = 1e-5: truncation O(h^2 V''') and rounding O(eps V / h), about
// 1e-8 of the largest force here.
TEST(ExternalFields, ForceIsMinusEnergyGradient) {
  RunInput input = input_from(fields_input(kAllFields));
  const auto reference = evaluate(input);
  const double h = 1e-5;
  double worst = 0.0, scale = 0.0;
  for (const Vec3& f : reference.force) scale = std::max(scale, norm(f));
  Particles& p = input.system.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const double x0 = p.position[i][a];
      p.position[i][a] = x0 + h;
      const double up = evaluate(input).evaluation.potential;
      p.position[i][a] = x0 - h;
      const double down = evaluate(input).evaluation.potential;
      p.position[i][a] = x0;
      worst = std::max(worst, std::abs(-(up - down) / (2 * h) - reference.force[i][a]));
    }
  }
  EXPECT_LT(worst, 1e-6 * std::max(1.0, scale)) << "largest |F| = " << scale;
}

// Each field alone, then all three: the energy of the three is the sum of the three alone,
// and it appears once, as "external" (a CSV column or an H5MD series per name).
TEST(ExternalFields, SeveralFieldsAreOneSummedTerm) {
  double sum = 0.0;
  for (const std::string field :
       {"gravity = [0.3, -0.2, -9.8]\n",
        "inverse_square = { strength = 2.5, center = [-20.0, -20.0, -20.0] }\n",
        "radial_polynomial = { degree = 3, coefficients = [0.5, 0.01, -2e-4, 1e-6], "
        "center = [1.0, 2.0, 3.0] }\n"}) {
    sum += evaluate(input_from(fields_input(field))).evaluation.potential -
           evaluate(input_from(fields_input(""))).evaluation.potential;
  }
  const ForceEvaluation all = evaluate(input_from(fields_input(kAllFields))).evaluation;
  int external = 0;
  double energy = 0.0;
  for (std::size_t t = 0; t < all.names.size(); ++t) {
    for (std::size_t u = 0; u < t; ++u) EXPECT_NE(all.names[t], all.names[u]) << "duplicate";
    if (all.names[t] == "external") ++external, energy = all.energies[t];
  }
  EXPECT_EQ(external, 1);
  EXPECT_NEAR(energy, sum, 1e-12 * std::abs(sum));
}

}  // namespace
}  // namespace deli
