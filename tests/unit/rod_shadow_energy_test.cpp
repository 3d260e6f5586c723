// The thermo's shadow energy with rods (verlet_shadow_energy_on_rods) solves the rods'
// multipliers (G M^-1 G^T) mu = G M^-1 F by a tridiagonal sweep when the rods are numbered
// along their chains, by a sparse LDL^T factorisation otherwise. The same rods in the two
// numberings are the same equations with their rows permuted: the two energies agree to
// rounding (the expected value is the sparse factorisation's, a second method).
#include <gtest/gtest.h>

#include <cmath>

#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "integrators/shadow_correction.hpp"
#include "support/test_systems.hpp"

namespace deli {
namespace {

TEST(RodShadowEnergy, ChainSweepIsTheSparseFactorisation) {
  RunInput input = testing::thirty_bead_lj_rod_chains();
  System& system = input.system;
  Gvi gvi(*input.force_field, input.constraints, input.gvi, system.particles);
  gvi.setup(system);
  for (int n = 0; n < 5; ++n) gvi.step(system, true);
  const std::vector<Constraint>& along = input.constraints.equalities;
  ASSERT_EQ(along.size(), 40u * 29u);
  // Along the chains: rod k and k+1 share a bead within a chain.
  for (std::size_t k = 0; k + 1 < along.size(); ++k) {
    if ((k + 1) % 29 == 0) continue;
    ASSERT_TRUE(along[k].j == along[k + 1].i || along[k].i == along[k + 1].j) << k;
  }
  // The rods of chains 2c and 2c+1 interleaved: no two rods of a chain are neighbours in
  // the list.
  std::vector<Constraint> interleaved;
  for (std::size_t c = 0; c < 40; c += 2) {
    for (std::size_t k = 0; k < 29; ++k) {
      interleaved.push_back(along[c * 29 + k]);
      interleaved.push_back(along[(c + 1) * 29 + k]);
    }
  }
  const double h = input.gvi.timestep;
  const std::optional<double> sweep = verlet_shadow_energy_on_rods(gvi.forces(), system, h, along);
  const std::optional<double> sparse =
      verlet_shadow_energy_on_rods(gvi.forces(), system, h, interleaved);
  ASSERT_TRUE(sweep && sparse);
  const std::optional<double> plain = gvi.forces().verlet_shadow_energy(system, h);
  ASSERT_TRUE(plain);
  // The rod terms matter here (far beyond the tolerance below).
  EXPECT_GT(std::abs(*sweep - *plain), 1e-6 * std::abs(*plain));
  EXPECT_NEAR(*sweep, *sparse, 1e-12 * std::abs(*sparse));
}

}  // namespace
}  // namespace deli
