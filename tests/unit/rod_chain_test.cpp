// The rod-chain kernels hold every rod to the solver tolerance and give, bit for bit, the
// generic solvers' positions, impulses, virial and projected momenta (a chain across a
// periodic boundary, unequal masses, rods numbered either way round); clusters that are
// not linear chains of rods have no chain form.
#include "solvers/rod_chain.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>

#include "constraints/constraint_set.hpp"
#include "solvers/momentum_update.hpp"
#include "solvers/position_update.hpp"

namespace deli {
namespace {

struct Chain {
  LocalCluster cluster;
  std::vector<Vec3> q, delta, p;
};

// A random walk of n beads with unit steps starting near the box's upper x face (so that it
// crosses the periodic boundary), wrapped into the box; a random step and momenta.
Chain random_chain(std::size_t n, const Box& box, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> mass(0.5, 2.0);
  Chain c;
  Vec3 x{box.hi().x - 1.5, 0.3, -0.2};
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0) {
      Vec3 step{normal(rng), normal(rng), normal(rng)};
      x += step * (1.0 / norm(step));
    }
    Vec3 wrapped = x;
    std::array<int, 3> image{};
    box.wrap(wrapped, image);
    c.q.push_back(wrapped);
    c.delta.push_back(Vec3{normal(rng), normal(rng), normal(rng)} * 0.02);
    c.p.push_back(Vec3{normal(rng), normal(rng), normal(rng)});
    c.cluster.particles.push_back(static_cast<std::int32_t>(k));
    c.cluster.inverse_mass.push_back(1.0 / mass(rng));
  }
  for (std::size_t k = 0; k + 1 < n; ++k) {
    Constraint rod;
    rod.kind = ConstraintKind::rod;
    // Every other rod written from its higher-numbered bead.
    rod.i = static_cast<std::int32_t>(k % 2 ? k + 1 : k);
    rod.j = static_cast<std::int32_t>(k % 2 ? k : k + 1);
    rod.length = 1.0;
    c.cluster.rows.push_back(rod);
    c.cluster.global_rows.push_back(static_cast<std::int32_t>(k));
  }
  return c;
}

// The generic solvers' position update of the chain from q (its rows all equalities).
PositionUpdate generic_position_update(const Chain& c, const std::vector<Vec3>& q, double h,
                                       const Box& box, double tolerance,
                                       const SolverLimits& limits) {
  std::vector<Vec3> x0 = c.delta;
  for (std::size_t k = 0; k < x0.size(); ++k) x0[k] += q[k];
  return solve_position_update(ClusterRows(c.cluster),
                               std::vector<bool>(c.cluster.rows.size(), true), q, x0, h, box,
                               tolerance, limits.newton, limits.line_search);
}

// Every component equal (EXPECT_EQ: the same numbers, bit for bit but for the sign of zero).
void expect_equal_components(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].x, b[k].x);
    EXPECT_EQ(a[k].y, b[k].y);
    EXPECT_EQ(a[k].z, b[k].z);
  }
}

// The lockstep momentum projection of `chains` at x from momenta p against each chain's
// kernel alone (`alone`: the same chains made separately): every chain solved, the momenta and
// virial terms the same bit for bit. Returns the lockstep projection's momenta.
std::vector<Vec3> expect_lanes_project_as_alone(const std::vector<const RodChain*>& chains,
                                                const std::vector<std::unique_ptr<RodChain>>& alone,
                                                const std::vector<Vec3>& x,
                                                const std::vector<Vec3>& p, const Box& box,
                                                RodChainLanes& lanes, RodChainWorkspace& work) {
  const std::size_t count = chains.size();
  std::vector<Vec3> p_alone = p, p_lanes = p;
  bool solved[RodChainLanes::width];
  double virial[RodChainLanes::width];
  RodChain::project_momenta_lanes(chains.data(), count, x.data(), p_lanes.data(), box, lanes,
                                  virial, solved);
  for (std::size_t c = 0; c < count; ++c) {
    EXPECT_TRUE(solved[c]) << "chain " << c;
    double virial_alone = 0.0;
    EXPECT_TRUE(alone[c]->project_momenta(x.data(), p_alone.data(), box, work, virial_alone));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(virial[c]), std::bit_cast<std::uint64_t>(virial_alone))
        << "chain " << c;
    EXPECT_NE(virial_alone, 0.0) << "chain " << c;
  }
  expect_equal_components(p_lanes, p_alone);
  return p_lanes;
}

TEST(RodChain, SameNumbersAsTheGenericSolvers) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Chain c = random_chain(40, box, seed);
    const std::unique_ptr<RodChain> chain = RodChain::make(c.cluster);
    ASSERT_NE(chain, nullptr);
    const ClusterRows structure(c.cluster);
    std::vector<Vec3> x0 = c.delta;
    for (std::size_t k = 0; k < x0.size(); ++k) x0[k] += c.q[k];
    const PositionUpdate generic = generic_position_update(c, c.q, h, box, tolerance, limits);
    ASSERT_TRUE(generic.status.converged);
    RodChainWorkspace work;
    std::vector<Vec3> impulse(c.q.size());
    double virial = 0.0;
    SolverStatus status;
    ASSERT_TRUE(chain->solve_positions(c.q.data(), c.delta.data(), h, box, tolerance, limits.newton,
                                       limits.line_search, work, impulse.data(), virial, status));
    EXPECT_EQ(status.iterations, generic.status.iterations);
    double generic_virial = 0.0;
    for (std::size_t r = 0; r < c.cluster.rows.size(); ++r) {
      const Constraint& rod = c.cluster.rows[r];
      generic_virial += generic.z(static_cast<Eigen::Index>(r)) *
                        norm(box.minimum_image(c.q[rod.i] - c.q[rod.j]));
    }
    EXPECT_EQ(virial, generic_virial);
    expect_equal_components(impulse, generic.impulse);
    // The rods are held at the end positions.
    std::vector<Vec3> x(c.q.size());
    for (std::size_t k = 0; k < x.size(); ++k) {
      x[k] = x0[k] + impulse[k] * (h * c.cluster.inverse_mass[k]);
    }
    for (const Constraint& rod : c.cluster.rows) {
      EXPECT_LE(std::abs(norm(box.minimum_image(x[rod.i] - x[rod.j])) - 1.0), tolerance);
    }

    // Momentum projection at x.
    std::vector<Vec3> p_generic = c.p, p_chain = c.p;
    Eigen::VectorXd mu;
    ASSERT_TRUE(project_momentum(structure, x, p_generic, box, 1e-10, mu).converged);
    double momentum_virial = 0.0;
    ASSERT_TRUE(chain->project_momenta(x.data(), p_chain.data(), box, work, momentum_virial));
    double generic_momentum_virial = 0.0;
    for (std::size_t r = 0; r < c.cluster.rows.size(); ++r) {
      const Constraint& rod = c.cluster.rows[r];
      generic_momentum_virial +=
          mu(static_cast<Eigen::Index>(r)) * norm(box.minimum_image(x[rod.i] - x[rod.j]));
    }
    EXPECT_EQ(momentum_virial, generic_momentum_virial);
    expect_equal_components(p_chain, p_generic);
    // Tangent to every rod.
    for (const Constraint& rod : c.cluster.rows) {
      const Vec3 d = box.minimum_image(x[rod.i] - x[rod.j]);
      const Vec3 v = p_chain[rod.i] * c.cluster.inverse_mass[rod.i] -
                     p_chain[rod.j] * c.cluster.inverse_mass[rod.j];
      EXPECT_LE(std::abs(dot(d, v)), 1e-12);
    }
  }
}

// The start-of-step directions are taken from the last momentum projection when the
// positions are bit for bit those it saw (the next step of an unwrapped chain), computed
// otherwise (positions wrapped meanwhile): the solve gives the same numbers as a chain that
// never projected.
TEST(RodChain, RememberedDirectionsChangeNothing) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  const Chain c = random_chain(40, box, 5);
  std::vector<Vec3> shifted = c.q;  // the same chain one period over: other bits, same rods
  for (Vec3& x : shifted) x.y += 7.0;
  const std::vector<Vec3>* starts[] = {&c.q, &shifted};
  for (const std::vector<Vec3>* q : starts) {
    const std::unique_ptr<RodChain> fresh = RodChain::make(c.cluster);
    const std::unique_ptr<RodChain> projected = RodChain::make(c.cluster);
    RodChainWorkspace work;
    std::vector<Vec3> p = c.p;
    double momentum_virial = 0.0;
    ASSERT_TRUE(projected->project_momenta(c.q.data(), p.data(), box, work, momentum_virial));
    std::vector<Vec3> impulse_fresh(c.q.size()), impulse_projected(c.q.size());
    double virial_fresh = 0.0, virial_projected = 0.0;
    SolverStatus status;
    ASSERT_TRUE(fresh->solve_positions(q->data(), c.delta.data(), h, box, tolerance, limits.newton,
                                       limits.line_search, work, impulse_fresh.data(), virial_fresh,
                                       status));
    ASSERT_TRUE(projected->solve_positions(q->data(), c.delta.data(), h, box, tolerance,
                                           limits.newton, limits.line_search, work,
                                           impulse_projected.data(), virial_projected, status));
    EXPECT_EQ(virial_projected, virial_fresh);
    expect_equal_components(impulse_projected, impulse_fresh);
  }
}

// Each rod's minimum image starts from the periodic image it had the last time: when
// particles are wrapped differently in between (here every bead left of the box's middle
// moved one period up, so that the rods crossing the middle change image), the stale image
// must be noticed and the numbers stay those of the generic solvers, bit for bit.
TEST(RodChain, RememberedImagesChangeNothing) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  const Chain c = random_chain(40, box, 6);
  std::vector<Vec3> rewrapped = c.q;
  for (Vec3& x : rewrapped) {
    if (x.x < 3.0) x.x += 6.0;
  }
  int changed_images = 0;
  for (const Constraint& rod : c.cluster.rows) {
    changed_images += (c.q[rod.i].x < 3.0) != (c.q[rod.j].x < 3.0);
  }
  ASSERT_GT(changed_images, 0);

  const std::unique_ptr<RodChain> chain = RodChain::make(c.cluster);
  RodChainWorkspace work;
  std::vector<Vec3> impulse(c.q.size());
  double virial = 0.0;
  SolverStatus status;
  ASSERT_TRUE(chain->solve_positions(c.q.data(), c.delta.data(), h, box, tolerance, limits.newton,
                                     limits.line_search, work, impulse.data(), virial, status));

  const PositionUpdate generic = generic_position_update(c, rewrapped, h, box, tolerance, limits);
  ASSERT_TRUE(generic.status.converged);
  ASSERT_TRUE(chain->solve_positions(rewrapped.data(), c.delta.data(), h, box, tolerance,
                                     limits.newton, limits.line_search, work, impulse.data(),
                                     virial, status));
  EXPECT_EQ(status.iterations, generic.status.iterations);
  expect_equal_components(impulse, generic.impulse);

  // The momentum projection at the original wrapping after the rewrapped solve.
  std::vector<Vec3> p_generic = c.p, p_chain = c.p;
  Eigen::VectorXd mu;
  ASSERT_TRUE(project_momentum(ClusterRows(c.cluster), c.q, p_generic, box, 1e-10, mu).converged);
  double momentum_virial = 0.0;
  ASSERT_TRUE(chain->project_momenta(c.q.data(), p_chain.data(), box, work, momentum_virial));
  expect_equal_components(p_chain, p_generic);
}

// The constraint checks' largest |f| / L of a chain, from the lengths its last momentum
// projection computed when the positions are those it saw, else computed: both are gap_of's
// numbers (the generic check over the rows), bit for bit.
TEST(RodChain, LargestDeviationIsGapOfs) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const Chain c = random_chain(40, box, 7);
  std::vector<Vec3> x = c.q;  // rods off their length by about the displacement, 0.02
  for (std::size_t k = 0; k < x.size(); ++k) x[k] += c.delta[k];
  auto by_gap_of = [&](const std::vector<Vec3>& at) {
    double largest = 0.0;
    for (const Constraint& rod : c.cluster.rows) {
      largest = std::max(largest, std::abs(gap_of(rod, at.data(), box)) / rod.length);
    }
    return largest;
  };
  const std::unique_ptr<RodChain> chain = RodChain::make(c.cluster);
  RodChainWorkspace work;
  std::vector<Vec3> p = c.p;
  double momentum_virial = 0.0;
  ASSERT_TRUE(chain->project_momenta(x.data(), p.data(), box, work, momentum_virial));
  ASSERT_GT(by_gap_of(x), 1e-3);
  EXPECT_EQ(chain->largest_relative_deviation(x.data(), box, work, 0.0), by_gap_of(x));
  EXPECT_EQ(chain->largest_relative_deviation(c.q.data(), box, work, 0.0), by_gap_of(c.q));
  EXPECT_EQ(chain->largest_relative_deviation(x.data(), box, work, 5.0), 5.0);
}

TEST(RodChain, OnlyLinearChainsOfRods) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  Chain c = random_chain(6, box, 4);
  EXPECT_NE(RodChain::make(c.cluster), nullptr);
  LocalCluster branched = c.cluster;
  branched.rows[2].i = 1;  // rods 0 and 2 share bead 1: a branch
  EXPECT_EQ(RodChain::make(branched), nullptr);
  LocalCluster contact = c.cluster;
  contact.rows[1].kind = ConstraintKind::sphere_pair;
  EXPECT_EQ(RodChain::make(contact), nullptr);
  LocalCluster loop = c.cluster;
  Constraint closing = loop.rows[0];
  closing.i = 0;
  closing.j = 5;
  loop.rows.push_back(closing);
  EXPECT_EQ(RodChain::make(loop), nullptr);
}

// The lockstep kernels (one chain per vector lane) against the chain kernel run alone, bit
// for bit, on eight chains of 40 beads at once: unequal masses, rods written either way
// round, chains across the periodic boundary, one chain held from the start (no step), and
// one with a displacement so large that its Newton needs a line-search halving, which the
// lockstep kernel leaves to the caller (the chain kernel alone then solves it).
TEST(RodChain, LanesGiveTheChainKernelsNumbers) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  constexpr std::size_t count = RodChainLanes::width, beads = 40;
  std::vector<Vec3> q, delta, p;
  std::vector<std::unique_ptr<RodChain>> alone, lanes_chains;
  for (std::size_t c = 0; c < count; ++c) {
    Chain chain = random_chain(beads, box, 20 + c);
    for (std::int32_t& particle : chain.cluster.particles) {
      particle += static_cast<std::int32_t>(c * beads);
    }
    // Chain 5 (seed 25) at 14 times the displacement needs a halving (found by trying).
    const double scale = c == 5 ? 14.0 : (c == 6 ? 0.0 : 1.0);
    for (std::size_t k = 0; k < beads; ++k) {
      q.push_back(chain.q[k]);
      delta.push_back(chain.delta[k] * scale);
      p.push_back(chain.p[k]);
    }
    alone.push_back(RodChain::make(chain.cluster));
    lanes_chains.push_back(RodChain::make(chain.cluster));
    ASSERT_NE(alone.back(), nullptr);
  }
  std::vector<const RodChain*> chains;
  for (const auto& chain : lanes_chains) chains.push_back(chain.get());

  std::vector<Vec3> impulse_alone(q.size()), impulse_lanes(q.size());
  RodChainWorkspace work;
  RodChainLanes lanes;
  double virial[count];
  SolverStatus status[count];
  bool solved[count];
  RodChain::solve_positions_lanes(chains.data(), count, q.data(), delta.data(), h, box, tolerance,
                                  limits.newton, lanes, impulse_lanes.data(), virial, status,
                                  solved);
  for (std::size_t c = 0; c < count; ++c) {
    double virial_alone = 0.0;
    SolverStatus status_alone;
    ASSERT_TRUE(alone[c]->solve_positions(q.data(), delta.data(), h, box, tolerance, limits.newton,
                                          limits.line_search, work, impulse_alone.data(),
                                          virial_alone, status_alone));
    // Only the chain that needs a halving is left unsolved.
    EXPECT_EQ(solved[c], c != 5) << "chain " << c;
    if (!solved[c]) {
      double redone = 0.0;
      ASSERT_TRUE(chains[c]->solve_positions(q.data(), delta.data(), h, box, tolerance,
                                             limits.newton, limits.line_search, work,
                                             impulse_lanes.data(), redone, status[c]));
      virial[c] = redone;
    }
    EXPECT_EQ(virial[c], virial_alone) << "chain " << c;
    EXPECT_EQ(status[c].iterations, status_alone.iterations) << "chain " << c;
    EXPECT_EQ(status[c].residual, status_alone.residual) << "chain " << c;
  }
  EXPECT_EQ(status[6].iterations, 0);
  expect_equal_components(impulse_lanes, impulse_alone);

  // Momentum projection at the end positions.
  std::vector<Vec3> x(q.size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = q[k] + delta[k] + impulse_alone[k] * h;
  expect_lanes_project_as_alone(chains, alone, x, p, box, lanes, work);
}

// Eight chains numbered one after another (lane l's bead b is particle base + l n + b): the
// lockstep kernels move their numbers by 8 x 8 blocks of the per-particle arrays, and the
// numbers past the last whole block one by one (31 beads: 93 numbers a chain, 11 blocks and
// 5 more; 40 beads: 15 blocks). The impulses and momenta are the chain kernel's alone, bit
// for bit, and the particles before and after the group keep their impulse and momentum.
TEST(RodChain, ConsecutiveChainsMovedByBlocksGiveTheChainKernelsNumbers) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  constexpr std::size_t count = RodChainLanes::width, before = 5, after = 3;
  for (const std::size_t beads : {31, 40}) {
    std::vector<Vec3> q(before), delta(before), p(before);
    std::vector<std::unique_ptr<RodChain>> alone, lanes_chains;
    for (std::size_t c = 0; c < count; ++c) {
      Chain chain = random_chain(beads, box, 60 + c);
      for (std::int32_t& particle : chain.cluster.particles) {
        particle += static_cast<std::int32_t>(before + c * beads);
      }
      q.insert(q.end(), chain.q.begin(), chain.q.end());
      delta.insert(delta.end(), chain.delta.begin(), chain.delta.end());
      p.insert(p.end(), chain.p.begin(), chain.p.end());
      alone.push_back(RodChain::make(chain.cluster));
      lanes_chains.push_back(RodChain::make(chain.cluster));
    }
    q.resize(q.size() + after);
    delta.resize(delta.size() + after);
    p.resize(p.size() + after);
    std::vector<const RodChain*> chains;
    for (const auto& chain : lanes_chains) chains.push_back(chain.get());
    // Outside the group: values no kernel may touch.
    const Vec3 untouched{-7.0, 8.5, 0.25};
    std::vector<Vec3> impulse_alone(q.size(), untouched), impulse_lanes(q.size(), untouched);
    RodChainWorkspace work;
    RodChainLanes lanes;
    double virial[count];
    SolverStatus status[count];
    bool solved[count];
    RodChain::solve_positions_lanes(chains.data(), count, q.data(), delta.data(), h, box, tolerance,
                                    limits.newton, lanes, impulse_lanes.data(), virial, status,
                                    solved);
    ASSERT_EQ(lanes.across.groups.size(), 1u);
    EXPECT_EQ(lanes.across.groups[0].consecutive, static_cast<std::int64_t>(before));
    for (std::size_t c = 0; c < count; ++c) {
      ASSERT_TRUE(solved[c]) << beads << " beads, chain " << c;
      double virial_alone = 0.0;
      SolverStatus status_alone;
      ASSERT_TRUE(alone[c]->solve_positions(q.data(), delta.data(), h, box, tolerance,
                                            limits.newton, limits.line_search, work,
                                            impulse_alone.data(), virial_alone, status_alone));
      EXPECT_EQ(virial[c], virial_alone) << beads << " beads, chain " << c;
      EXPECT_EQ(status[c].iterations, status_alone.iterations) << beads << " beads, chain " << c;
    }
    expect_equal_components(impulse_lanes, impulse_alone);
    for (std::size_t k : {std::size_t{0}, before - 1, q.size() - after, q.size() - 1}) {
      EXPECT_EQ(impulse_lanes[k].x, untouched.x) << "particle " << k;
      EXPECT_EQ(impulse_lanes[k].z, untouched.z) << "particle " << k;
    }

    std::vector<Vec3> x(q.size());
    for (std::size_t k = 0; k < x.size(); ++k) x[k] = q[k] + delta[k] + impulse_alone[k] * h;
    for (std::size_t k = 0; k < before; ++k) p[k] = untouched;
    for (std::size_t k = q.size() - after; k < q.size(); ++k) p[k] = untouched;
    const std::vector<Vec3> p_lanes =
        expect_lanes_project_as_alone(chains, alone, x, p, box, lanes, work);
    EXPECT_EQ(p_lanes.front().y, untouched.y);
    EXPECT_EQ(p_lanes.back().y, untouched.y);

    // Every chain held where it starts (no displacement): no Newton step in any lane, and the
    // impulses are the zero ones of the chain kernel, not those the lanes made last.
    const std::vector<Vec3> still(q.size());
    std::vector<Vec3> held_lanes(q.size(), untouched), held_alone(q.size(), untouched);
    RodChain::solve_positions_lanes(chains.data(), count, q.data(), still.data(), h, box, tolerance,
                                    limits.newton, lanes, held_lanes.data(), virial, status,
                                    solved);
    for (std::size_t c = 0; c < count; ++c) {
      ASSERT_TRUE(solved[c]);
      EXPECT_EQ(status[c].iterations, 0);
      double virial_alone = 0.0;
      SolverStatus status_alone;
      ASSERT_TRUE(alone[c]->solve_positions(q.data(), still.data(), h, box, tolerance,
                                            limits.newton, limits.line_search, work,
                                            held_alone.data(), virial_alone, status_alone));
    }
    expect_equal_components(held_lanes, held_alone);
  }
}

// A group of fewer chains than lanes (the empty lanes repeat the first chain), solved three
// times with the same workspace: again at the same step (the group's interleaved constants
// and images kept from the first solve) and at another step (remade). Every time the chain
// kernel alone gives the same numbers bit for bit, positions and momenta.
TEST(RodChain, AShortGroupSolvedAgainGivesTheChainKernelsNumbers) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double tolerance = 1e-12;
  const SolverLimits limits;
  constexpr std::size_t count = 3, beads = 30;
  std::vector<Vec3> q, delta, p;
  std::vector<std::unique_ptr<RodChain>> alone, lanes_chains;
  for (std::size_t c = 0; c < count; ++c) {
    Chain chain = random_chain(beads, box, 40 + c);
    for (std::int32_t& particle : chain.cluster.particles) {
      particle += static_cast<std::int32_t>(c * beads);
    }
    q.insert(q.end(), chain.q.begin(), chain.q.end());
    delta.insert(delta.end(), chain.delta.begin(), chain.delta.end());
    p.insert(p.end(), chain.p.begin(), chain.p.end());
    alone.push_back(RodChain::make(chain.cluster));
    lanes_chains.push_back(RodChain::make(chain.cluster));
  }
  std::vector<const RodChain*> chains;
  for (const auto& chain : lanes_chains) chains.push_back(chain.get());
  RodChainWorkspace work;
  RodChainLanes lanes;
  for (const double h : {0.005, 0.005, 0.004}) {
    std::vector<Vec3> impulse_alone(q.size()), impulse_lanes(q.size());
    double virial[RodChainLanes::width];
    SolverStatus status[RodChainLanes::width];
    bool solved[RodChainLanes::width];
    RodChain::solve_positions_lanes(chains.data(), count, q.data(), delta.data(), h, box, tolerance,
                                    limits.newton, lanes, impulse_lanes.data(), virial, status,
                                    solved);
    for (std::size_t c = 0; c < count; ++c) {
      ASSERT_TRUE(solved[c]) << "chain " << c << ", h " << h;
      double virial_alone = 0.0;
      SolverStatus status_alone;
      ASSERT_TRUE(alone[c]->solve_positions(q.data(), delta.data(), h, box, tolerance,
                                            limits.newton, limits.line_search, work,
                                            impulse_alone.data(), virial_alone, status_alone));
      EXPECT_EQ(virial[c], virial_alone) << "chain " << c << ", h " << h;
      EXPECT_EQ(status[c].iterations, status_alone.iterations) << "chain " << c << ", h " << h;
      EXPECT_EQ(status[c].residual, status_alone.residual) << "chain " << c << ", h " << h;
    }
    expect_equal_components(impulse_lanes, impulse_alone);
    std::vector<Vec3> x(q.size());
    for (std::size_t k = 0; k < x.size(); ++k) x[k] = q[k] + delta[k] + impulse_alone[k] * h;
    expect_lanes_project_as_alone(chains, alone, x, p, box, lanes, work);
  }
}

// A lane group's worth of random chains of `beads` beads (seeds from `seed`), chain c's
// particles c * beads onwards, chain 2's numbered backwards where asked; move(c, x) may shift
// chain c's start positions, bead by bead.
struct LaneChains {
  std::vector<Vec3> q, delta, p;
  std::vector<LocalCluster> clusters;
  std::vector<std::unique_ptr<RodChain>> owned;
  std::vector<const RodChain*> chains;
};
template <class Move>
LaneChains lane_chains(std::size_t beads, const Box& box, std::uint64_t seed, bool backwards,
                       Move&& move) {
  constexpr std::size_t count = RodChainLanes::width;
  LaneChains made;
  made.q.resize(count * beads);
  made.delta.resize(count * beads);
  made.p.resize(count * beads);
  for (std::size_t c = 0; c < count; ++c) {
    Chain chain = random_chain(beads, box, seed + c);
    for (std::size_t k = 0; k < beads; ++k) {
      const std::size_t particle = c * beads + (backwards && c == 2 ? beads - 1 - k : k);
      chain.cluster.particles[k] = static_cast<std::int32_t>(particle);
      move(c, chain.q[k]);
      made.q[particle] = chain.q[k];
      made.delta[particle] = chain.delta[k];
      made.p[particle] = chain.p[k];
    }
    made.clusters.push_back(chain.cluster);
  }
  for (const LocalCluster& cluster : made.clusters) {
    made.owned.push_back(RodChain::make(cluster));
    made.chains.push_back(made.owned.back().get());
  }
  return made;
}

// The directions a lockstep projection remembers stay in its group's lanes. Whoever meets
// the chains next gives the numbers of chains that never remembered anything: the largest
// deviation, a subset solved in another group, a chain solved alone (which makes its
// directions again), and the first group again (lanes remembered in it, alone and in the
// other group). Four of the chains cross the periodic boundary; one has its particles
// numbered backwards.
TEST(RodChain, DirectionsRememberedInLanesGiveFreshChainsNumbers) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  constexpr std::size_t count = RodChainLanes::width, beads = 30;
  // Half the chains moved away from the boundary; chain 2's particles numbered backwards.
  LaneChains made = lane_chains(beads, box, 60, true, [&](std::size_t c, Vec3& x) {
    if (c % 2) x = box.minimum_image(x - Vec3{2.5, 0, 0});
  });
  std::vector<Vec3>&q = made.q, &p = made.p;
  const std::vector<Vec3>& delta = made.delta;
  const std::vector<LocalCluster>& clusters = made.clusters;
  const std::vector<const RodChain*>& chains = made.chains;
  RodChainWorkspace work;
  RodChainLanes lanes;
  bool solved[count];
  double virial[count];
  // The start positions are where the projection left them, as at every step of a run.
  RodChain::project_momenta_lanes(chains.data(), count, q.data(), p.data(), box, lanes, virial,
                                  solved);
  for (std::size_t c = 0; c < count; ++c) ASSERT_TRUE(solved[c]);

  for (std::size_t c = 0; c < count; ++c) {
    const std::unique_ptr<RodChain> fresh = RodChain::make(clusters[c]);
    EXPECT_EQ(chains[c]->largest_relative_deviation(q.data(), box, work, 0.0),
              fresh->largest_relative_deviation(q.data(), box, work, 0.0))
        << "chain " << c;
  }
  // Each chain's position solve by a chain that remembers nothing.
  std::vector<Vec3> impulse_fresh(q.size());
  double virial_fresh[count];
  for (std::size_t c = 0; c < count; ++c) {
    const std::unique_ptr<RodChain> fresh = RodChain::make(clusters[c]);
    SolverStatus status;
    virial_fresh[c] = 0.0;
    ASSERT_TRUE(fresh->solve_positions(q.data(), delta.data(), h, box, tolerance, limits.newton,
                                       limits.line_search, work, impulse_fresh.data(),
                                       virial_fresh[c], status));
  }
  auto expect_fresh = [&](const std::vector<Vec3>& impulse, std::size_t first, std::size_t end) {
    for (std::size_t k = first * beads; k < end * beads; ++k) {
      EXPECT_EQ(impulse[k].x, impulse_fresh[k].x) << "bead " << k;
      EXPECT_EQ(impulse[k].y, impulse_fresh[k].y) << "bead " << k;
      EXPECT_EQ(impulse[k].z, impulse_fresh[k].z) << "bead " << k;
    }
  };
  SolverStatus status[count];
  // Chains 0-3 in another group.
  std::vector<Vec3> impulse(q.size());
  RodChain::solve_positions_lanes(chains.data(), 4, q.data(), delta.data(), h, box, tolerance,
                                  limits.newton, lanes, impulse.data(), virial, status, solved);
  for (std::size_t c = 0; c < 4; ++c) {
    ASSERT_TRUE(solved[c]) << "chain " << c;
    EXPECT_EQ(virial[c], virial_fresh[c]) << "chain " << c;
  }
  expect_fresh(impulse, 0, 4);
  // Chain 5 alone.
  double alone_virial = 0.0;
  SolverStatus alone_status;
  ASSERT_TRUE(chains[5]->solve_positions(q.data(), delta.data(), h, box, tolerance, limits.newton,
                                         limits.line_search, work, impulse.data(), alone_virial,
                                         alone_status));
  EXPECT_EQ(alone_virial, virial_fresh[5]);
  expect_fresh(impulse, 5, 6);
  // All of them in the first group again.
  std::fill(impulse.begin(), impulse.end(), Vec3{});
  RodChain::solve_positions_lanes(chains.data(), count, q.data(), delta.data(), h, box, tolerance,
                                  limits.newton, lanes, impulse.data(), virial, status, solved);
  for (std::size_t c = 0; c < count; ++c) {
    ASSERT_TRUE(solved[c]) << "chain " << c;
    EXPECT_EQ(virial[c], virial_fresh[c]) << "chain " << c;
  }
  expect_fresh(impulse, 0, count);
  // One bead of each of chains 1 and 2 (backwards) moved: their memos no longer hold.
  for (const std::size_t c : {std::size_t{1}, std::size_t{2}}) {
    q[c * beads + 5].x += 1e-3;
    const std::unique_ptr<RodChain> fresh = RodChain::make(clusters[c]);
    EXPECT_EQ(chains[c]->largest_relative_deviation(q.data(), box, work, 0.0),
              fresh->largest_relative_deviation(q.data(), box, work, 0.0))
        << "chain " << c;
  }
}

// A lockstep solve takes its start directions from the group's lanes only where the start
// positions are bit for bit those the projection saw there: the lanes' gather compares them.
// A bead moved after the projection (by 1e-9, or by one ulp), in the first numbers of the
// chain, in the middle, or among the numbers past its last whole 8 x 8 block (30 beads: 90
// numbers, 11 blocks), gives that chain the numbers of a chain that remembers nothing; the
// others are unchanged. Consecutive chains (moved by blocks) and a group with one chain
// numbered backwards (moved bead by bead).
TEST(RodChain, LanesNoticeStartPositionsMovedSinceTheProjection) {
  const Box box({0, 0, 0}, {6, 7, 8}, {true, true, true});
  const double h = 0.005, tolerance = 1e-12;
  const SolverLimits limits;
  constexpr std::size_t count = RodChainLanes::width, beads = 30;
  for (const bool backwards : {false, true}) {
    SCOPED_TRACE(backwards ? "chain 2 numbered backwards" : "consecutive chains");
    LaneChains made = lane_chains(beads, box, 80, backwards, [](std::size_t, Vec3&) {});
    std::vector<Vec3>&q = made.q, &p = made.p;
    const std::vector<Vec3>& delta = made.delta;
    const std::vector<LocalCluster>& clusters = made.clusters;
    const std::vector<const RodChain*>& chains = made.chains;
    RodChainLanes lanes;
    bool solved[count];
    double virial[count];
    RodChain::project_momenta_lanes(chains.data(), count, q.data(), p.data(), box, lanes, virial,
                                    solved);
    for (std::size_t c = 0; c < count; ++c) ASSERT_TRUE(solved[c]);
    // Chain 1: a middle bead; chain 2: its first particle; chain 3: its last bead's z (a
    // number past the blocks); chain 6: its first bead's y by one ulp.
    const std::size_t last = beads - 1;
    q[1 * beads + 12].x += 1e-9;
    q[2 * beads].y -= 1e-9;
    q[3 * beads + last].z += 1e-9;
    q[6 * beads].y = std::nextafter(q[6 * beads].y, 10.0);
    std::vector<Vec3> impulse(q.size()), impulse_fresh(q.size());
    SolverStatus status[count];
    RodChain::solve_positions_lanes(chains.data(), count, q.data(), delta.data(), h, box, tolerance,
                                    limits.newton, lanes, impulse.data(), virial, status, solved);
    RodChainWorkspace work;
    for (std::size_t c = 0; c < count; ++c) {
      ASSERT_TRUE(solved[c]) << "chain " << c;
      const std::unique_ptr<RodChain> fresh = RodChain::make(clusters[c]);
      double virial_fresh = 0.0;
      SolverStatus fresh_status;
      ASSERT_TRUE(fresh->solve_positions(q.data(), delta.data(), h, box, tolerance, limits.newton,
                                         limits.line_search, work, impulse_fresh.data(),
                                         virial_fresh, fresh_status));
      EXPECT_EQ(virial[c], virial_fresh) << "chain " << c;
      for (std::size_t k = c * beads; k < (c + 1) * beads; ++k) {
        EXPECT_EQ(impulse[k].x, impulse_fresh[k].x) << "chain " << c << " bead " << k;
        EXPECT_EQ(impulse[k].y, impulse_fresh[k].y) << "chain " << c << " bead " << k;
        EXPECT_EQ(impulse[k].z, impulse_fresh[k].z) << "chain " << c << " bead " << k;
      }
    }
  }
}

}  // namespace
}  // namespace deli
