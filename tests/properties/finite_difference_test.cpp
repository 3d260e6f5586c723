// Every force is minus the gradient of its energy, and the virial is minus the volume
// derivative: checked by central differences on random configurations.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pair/lennard_jones.hpp"
#include "pair/pair_coefficients.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

using testing::evaluate;
using testing::input_from;

struct Case {
  std::string name;
  std::string toml;
};
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.name;
}

std::string chains_input(const std::string& boundary, const std::string& forcefield,
                         bool angles = true, bool dihedrals = false) {
  return "[system]\nboundary = \"" + boundary +
         "\"\n[system.chains]\ncount = 12\nlength = 8\ndensity = 0.55\nbond_length = 0.97\n"
         "min_distance = 0.85\nangles = " +
         std::string(angles ? "true" : "false") +
         "\ndihedrals = " + std::string(dihedrals ? "true" : "false") + "\nseed = 7\n" +
         forcefield + "[integrator]\ntimestep = 0.005\n[run]\nsteps = 0\n";
}

const std::string kPairLj =
    "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\ncoeffs = [{types = [1, 1], epsilon = "
    "1.0, sigma = 1.0}]\n";
const std::string kBondedTail =
    "[forcefield.bond]\nstyle = \"harmonic\"\ncoeffs = [{type = 1, k = 100.0, r0 = 1.0}]\n"
    "[forcefield.angle]\nstyle = \"harmonic\"\ncoeffs = [{type = 1, k = 5.0, theta0 = 110.0}]\n";
// LAMMPS' angle_style cosine, E = K [1 + cos(theta)], of semiflexible chains.
const std::string kCosineAngleTail =
    "[forcefield.bond]\nstyle = \"harmonic\"\ncoeffs = [{type = 1, k = 100.0, r0 = 1.0}]\n"
    "[forcefield.angle]\nstyle = \"cosine\"\ncoeffs = [{type = 1, k = 1.5}]\n";
// LAMMPS' dihedral_style harmonic, E = K [1 + d cos(n phi)].
std::string dihedral_tail(double d, int n) {
  return kBondedTail +
         "[forcefield.dihedral]\nstyle = \"harmonic\"\ncoeffs = [{type = 1, k = 1.2, d = " +
         std::to_string(static_cast<int>(d)) + ", n = " + std::to_string(n) + "}]\n";
}
const std::string kFeneTail =
    "[forcefield.bond]\nstyle = \"fene\"\ncoeffs = [{type = 1, k = 30.0, r0 = 1.5, epsilon = "
    "1.0, sigma = 1.0}]\n";

std::vector<Case> cases() {
  const std::string lj_shifted =
      "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\nshift = true\ncoeffs = [{types = "
      "[1, 1], epsilon = 1.0, sigma = 1.0}]\n";
  const std::string wca =
      "[forcefield.pair]\nstyle = \"wca\"\ncoeffs = [{types = [1, 1], epsilon = 1.0, sigma = "
      "1.0}]\n";
  return {
      {"lj_harmonic_angle_periodic", chains_input("ppp", "[forcefield]\n" + kPairLj + kBondedTail)},
      {"lj_harmonic_angle_open", chains_input("fff", "[forcefield]\n" + kPairLj + kBondedTail)},
      {"lj_shifted_mixed_boundary",
       chains_input("ppf", "[forcefield]\n" + lj_shifted + kBondedTail)},
      {"lj_cosine_angle_mixed_boundary",
       chains_input("ppf", "[forcefield]\n" + kPairLj + kCosineAngleTail)},
      {"lj_harmonic_dihedral_minus_3_periodic",
       chains_input("ppp", "[forcefield]\n" + kPairLj + dihedral_tail(-1, 3), true, true)},
      {"lj_harmonic_dihedral_plus_1_mixed_boundary",
       chains_input("ppf", "[forcefield]\n" + kPairLj + dihedral_tail(1, 1), true, true)},
      {"wca_fene_kremer_grest", chains_input("ppp", "[forcefield]\n" + wca + kFeneTail, false)},
      {"lj_special_scaled",
       chains_input("ppp", "[forcefield]\n[forcefield.special_bonds]\nlj = [0.0, 0.5, 0.8]\n" +
                               lj_shifted + kBondedTail)},
  };
}

class FiniteDifference : public ::testing::TestWithParam<Case> {};

// Central difference with step h has error O(h^2 E''') and rounding O(eps E / h);
// h = 1e-5 sigma balances them at about 1e-7 relative for these smooth potentials.
TEST_P(FiniteDifference, ForceIsMinusEnergyGradient) {
  RunInput input = input_from(GetParam().toml);
  const auto reference = evaluate(input);
  ASSERT_GT(reference.evaluation.energies.size(), 0u);
  const double h = 1e-5;
  double worst = 0.0, scale = 0.0;
  for (const Vec3& f : reference.force) scale = std::max(scale, norm(f));
  Particles& p = input.system.particles;
  for (std::size_t i = 0; i < p.size(); i += 3) {
    for (int a = 0; a < 3; ++a) {
      const double x0 = p.position[i][a];
      p.position[i][a] = x0 + h;
      const double up = evaluate(input).evaluation.potential;
      p.position[i][a] = x0 - h;
      const double down = evaluate(input).evaluation.potential;
      p.position[i][a] = x0;
      const double numeric = -(up - down) / (2 * h);
      worst = std::max(worst, std::abs(numeric - reference.force[i][a]));
    }
  }
  EXPECT_LT(worst, 1e-6 * std::max(1.0, scale)) << "largest |F| = " << scale;
}

// dU/d(ln s) under x -> s x, L -> s L equals -W (the virial) for pair and bonded terms.
TEST_P(FiniteDifference, VirialIsMinusVolumeDerivative) {
  RunInput input = input_from(GetParam().toml);
  const double w = evaluate(input).evaluation.virial.trace();
  auto energy_scaled = [&](double s) {
    RunInput copy = input_from(GetParam().toml);
    const Box& b = input.system.box;
    copy.system.box = Box(b.lo() * s, b.hi() * s, b.periodic());
    for (Vec3& x : copy.system.particles.position) x *= s;
    return evaluate(copy).evaluation.potential;
  };
  const double h = 1e-6;
  const double dlns =
      (energy_scaled(1 + h) - energy_scaled(1 - h)) / (std::log(1 + h) - std::log(1 - h));
  EXPECT_NEAR(-dlns, w, 1e-6 * std::max(1.0, std::abs(w)));
}

// Newton's third law: the forces of an isolated system sum to zero.
TEST_P(FiniteDifference, ForcesSumToZero) {
  const RunInput input = input_from(GetParam().toml);
  const auto r = evaluate(input);
  Vec3 sum;
  double scale = 0.0;
  for (const Vec3& f : r.force) sum += f, scale = std::max(scale, norm(f));
  EXPECT_LT(norm(sum), 1e-12 * scale * static_cast<double>(r.force.size()));
}

// A step that does not tally (most steps) gets the same forces, bit for bit, and neither
// energy nor virial (ForceTerm::compute's contract: the terms skip those sums then).
TEST_P(FiniteDifference, UntalliedStepHasTheSameForcesAndNoSums) {
  const RunInput input = input_from(GetParam().toml);
  const auto tallied = evaluate(input);
  const auto untallied = evaluate(input, 0.5, false);
  ASSERT_EQ(untallied.force.size(), tallied.force.size());
  for (std::size_t i = 0; i < tallied.force.size(); ++i) {
    ASSERT_EQ(untallied.force[i].x, tallied.force[i].x) << i;
    ASSERT_EQ(untallied.force[i].y, tallied.force[i].y) << i;
    ASSERT_EQ(untallied.force[i].z, tallied.force[i].z) << i;
  }
  EXPECT_NE(tallied.evaluation.potential, 0.0);
  EXPECT_EQ(untallied.evaluation.potential, 0.0);
  EXPECT_EQ(untallied.evaluation.virial.trace(), 0.0);
  EXPECT_EQ(untallied.evaluation.virial.xy, 0.0);
}

INSTANTIATE_TEST_SUITE_P(AllForces, FiniteDifference, ::testing::ValuesIn(cases()),
                         [](const auto& info) { return info.param.name; });

// An unlike pair not given is mixed (Lorentz-Berthelot): its energy is the analytic LJ
// with eps = sqrt(e1 e2), sigma = (s1 + s2) / 2.
TEST(PairMixing, LorentzBerthelotMatchesAnalyticEnergy) {
  for (const double r : {0.9, 1.1, 1.7, 2.2}) {
    PairCoefficients coeffs(2, 3.0);
    coeffs.set(0, 0, {1.0, 1.0}, std::nullopt);  // epsilon, sigma
    coeffs.set(1, 1, {0.5, 1.4}, std::nullopt);
    ASSERT_TRUE(coeffs.resolve(Mixing::arithmetic, {MixRule::geometric, MixRule::chosen}).empty());
    const PairCoefficient& mixed = coeffs.at(0, 1);
    EXPECT_DOUBLE_EQ(mixed.values[0], std::sqrt(0.5));
    EXPECT_DOUBLE_EQ(mixed.values[1], 1.2);
    const auto params = LennardJones::make(mixed.values[0], mixed.values[1], mixed.cutoff);
    double f_over_r, e;
    LennardJones::evaluate(params, r * r, f_over_r, e);
    const double sr6 = std::pow(1.2 / r, 6);
    EXPECT_NEAR(e, 4 * std::sqrt(0.5) * (sr6 * sr6 - sr6), 1e-13);
  }
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// The pair Hessian blocks (used by shadow-energy reflections) against central differences
// of the forces: H v = -(F(x + e v) - F(x - e v)) / (2 e).
TEST(Hessian, PairBlocksMatchForceDifferences) {
  const std::string pair =
      "[forcefield.pair]\nstyle = \"lj/cut\"\ncutoff = 2.5\nshift = true\ncoeffs = [{types = "
      "[1, 1], epsilon = 1.0, sigma = 1.0}]\n[forcefield.special_bonds]\nlj = [0.0, 0.5, 1.0]\n";
  for (const std::string& bonds :
       {std::string("[forcefield.bond]\nstyle = \"harmonic\"\ncoeffs = [{type = 1, k = 100.0, r0 = "
                    "1.0}]\n"),
        std::string("[forcefield.bond]\nstyle = \"fene\"\ncoeffs = [{type = 1, k = 30.0, r0 = 1.5, "
                    "epsilon = 1.0, sigma = 1.0}]\n")}) {
    RunInput input =
        testing::input_from(chains_input("ppp", "[forcefield]\n" + pair + bonds, false));
    const Particles& p = input.system.particles;
    NeighborList list(input.force_field->neighbor_cutoff(), 0.5);
    const SpecialPairs special = find_special_pairs(input.system.topology, p.size());
    std::vector<std::array<std::int32_t, 2>> excluded(special.by_separation[0]);
    excluded.insert(excluded.end(), special.by_separation[1].begin(),
                    special.by_separation[1].end());
    list.set_exclusions(excluded);
    list.build(p.position, input.system.box);
    std::vector<PairHessian> blocks;
    ASSERT_TRUE(input.force_field->pair_hessians(input.system, list, {}, blocks));
    std::mt19937_64 rng(4);
    std::normal_distribution<double> normal;
    std::vector<Vec3> v(p.size());
    for (Vec3& vi : v) vi = {normal(rng), normal(rng), normal(rng)};
    std::vector<Eigen::Vector3d> hv(p.size(), Eigen::Vector3d::Zero());
    for (const PairHessian& b : blocks) {
      const Eigen::Vector3d dv(v[b.a].x - v[b.b].x, v[b.a].y - v[b.b].y, v[b.a].z - v[b.b].z);
      hv[b.a] += b.block * dv;
      hv[b.b] -= b.block * dv;
    }
    auto forces_at = [&](double e) {
      System moved = input.system;
      for (std::size_t i = 0; i < p.size(); ++i) moved.particles.position[i] += v[i] * e;
      std::vector<Vec3> f;
      input.force_field->compute(moved, list, f);
      return f;
    };
    const double e = 1e-6;
    const auto up = forces_at(e), down = forces_at(-e);
    double worst = 0, scale = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        const double numeric = -(up[i][a] - down[i][a]) / (2 * e);
        worst = std::max(worst, std::abs(numeric - hv[i](a)));
        scale = std::max(scale, std::abs(hv[i](a)));
      }
    }
    EXPECT_LT(worst, 1e-6 * std::max(1.0, scale));
  }
}

}  // namespace
}  // namespace deli
