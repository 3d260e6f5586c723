// The paper's examples (inputs/paper/) run to their stated lengths and show the paper's
// claims for GVI: bounded energy, exact angular momentum where it is conserved, no
// overlap, the cradle's energy error second order in h, linearised constraints losing
// the angular momentum the nonlinear ones keep.
#include <gtest/gtest.h>

#include <cmath>

#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "simulation/run_loop.hpp"
#include "support/energy_trend.hpp"
#include "support/short_runs.hpp"

namespace deli {
namespace {

struct Trace {
  std::vector<double> energy;
  std::vector<double> angular_z;
  double min_gap = 1e300;
  int gap_samples = 0;  // samples with rows within reach (a finite min_gap)
  double penetrations = 0;
  double max_relative_energy_error() const {
    double worst = 0;
    for (double e : energy) worst = std::max(worst, std::abs(e - energy.front()));
    return worst / std::abs(energy.front());
  }
  // Bounded or drifting: the fitted trend of (E - E0) / |E0| over the run against its
  // fluctuation about that line (support/energy_trend.hpp).
  testing::EnergyTrend trend() const {
    std::vector<double> error;
    for (double e : energy) error.push_back((e - energy.front()) / std::abs(energy.front()));
    return testing::energy_trend(error);
  }
  double max_angular_change() const {
    double worst = 0;
    for (double l : angular_z) worst = std::max(worst, std::abs(l - angular_z.front()));
    return worst;
  }
};

// No overlap beyond the tolerance, among samples that measured a gap: a run with none (no
// contact ever within reach) would pass vacuously, so that fails too.
::testing::AssertionResult no_overlap(const Trace& t) {
  if (t.gap_samples == 0) return ::testing::AssertionFailure() << "no sample measured a gap";
  if (t.min_gap > -1e-10) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "smallest gap " << t.min_gap;
}

// Bounded, not drifting: the energy error's fitted trend over the whole run stays below half
// its fluctuation about the fit. The paper's claim is boundedness (no figure to compare
// with); a drift as large as the oscillation would give 1 or more.
constexpr double kBounded = 0.5;

class RecordTrace final : public Observer {
 public:
  explicit RecordTrace(Trace& t) : t_(t) {}
  void on_thermo(const ThermoSample& s) override {
    t_.energy.push_back(s.total);
    if (s.angular_momentum) t_.angular_z.push_back(s.angular_momentum->z);
    for (const auto& [name, value] : s.integrator) {
      if (name == "min_gap" && std::isfinite(value)) {
        t_.min_gap = std::min(t_.min_gap, value);
        ++t_.gap_samples;
      }
      if (name == "penetrating_steps") t_.penetrations += value;
    }
  }

 private:
  Trace& t_;
};

Trace run_example(const std::string& name, std::int64_t steps = -1, std::int64_t every = 1) {
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/paper/" + name + ".toml");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  Trace trace;
  RecordTrace record(trace);
  run(input.system, gvi, steps < 0 ? input.steps : steps, every, {&record});
  return trace;
}

TEST(PaperExamples, ParticleDropKeepsItsEnergy) {
  const Trace t = run_example("particle_drop");
  EXPECT_LT(t.max_relative_energy_error(), 1e-12);
  EXPECT_TRUE(no_overlap(t));
}

TEST(PaperExamples, SpringAndSphereSmooth) {
  const Trace t = run_example("spring_sphere_smooth");
  std::printf("spring and sphere, smooth: max |dE|/E0 %.3e, trend/fluctuation %.3f, |dL| %.3e\n",
              t.max_relative_energy_error(), t.trend().ratio(), t.max_angular_change());
  // Regression pin: deli's own envelope (6.7e-2 at h = 0.5) plus a margin; the paper gives
  // no number, only the boundedness checked by the trend.
  EXPECT_LT(t.max_relative_energy_error(), 0.08);
  EXPECT_LT(t.trend().ratio(), kBounded);
  EXPECT_LT(t.max_angular_change(), 1e-11 * std::abs(t.angular_z.front()));
  EXPECT_TRUE(no_overlap(t));
}

TEST(PaperExamples, SpringAndSphereMixed) {
  const Trace t = run_example("spring_sphere_mixed");
  std::printf("spring and sphere, mixed: max |dE|/E0 %.3e, trend/fluctuation %.3f, |dL| %.3e\n",
              t.max_relative_energy_error(), t.trend().ratio(), t.max_angular_change());
  EXPECT_LT(t.max_relative_energy_error(), 0.12);  // regression pin: deli's 9.9e-2 at h = 0.5
  EXPECT_LT(t.max_angular_change(), 1e-11 * std::abs(t.angular_z.front()));
  EXPECT_TRUE(no_overlap(t));
}

TEST(PaperExamples, NonlinearOscillatorKeepsAngularMomentumLinearisedLosesIt) {
  const Trace exact = run_example("nonlinear_oscillator");
  const Trace linear = run_example("nonlinear_oscillator_linearized");
  std::printf("oscillator: |dE|/E0 %.3e, |dL| %.3e; linearised: |dE|/E0 %.3e, |dL| %.3e\n",
              exact.max_relative_energy_error(), exact.max_angular_change(),
              linear.max_relative_energy_error(), linear.max_angular_change());
  // Regression pins: deli's own envelopes (2.4e-2, 2.6e-2, every step) plus a margin. The
  // paper's claim tested independently of them: L kept by one, lost by the other.
  EXPECT_LT(exact.max_relative_energy_error(), 0.03);
  EXPECT_LT(exact.trend().ratio(), kBounded);
  EXPECT_LT(exact.max_angular_change(), 1e-12 * std::abs(exact.angular_z.front()));
  EXPECT_LT(linear.max_relative_energy_error(), 0.03);
  EXPECT_GT(linear.max_angular_change(), 0.1 * std::abs(linear.angular_z.front()));
}

// Energy error second order in h, stable across the sweep (20 time units each).
TEST(PaperExamples, NewtonsCradleSweep) {
  std::vector<double> errors;
  for (const char* h : {"0.03", "0.02", "0.01", "0.005"}) {
    const Trace t = run_example(std::string("newtons_cradle_h") + h);
    errors.push_back(t.max_relative_energy_error());
    EXPECT_LT(t.trend().ratio(), kBounded) << "h = " << h;
    EXPECT_TRUE(no_overlap(t)) << "h = " << h;
  }
  std::printf("cradle |dE|/|E0|: %.3e %.3e %.3e %.3e\n", errors[0], errors[1], errors[2],
              errors[3]);
  EXPECT_LT(errors[2], 5e-5);  // regression pin: deli's 2.2e-5 at h = 0.01
  // The independent check: a second-order method's error falls by 4 when h halves.
  const double ratio = errors[2] / errors[3];
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.0);
}

// The pogo stick to the paper's 1e5 time units (1e6 steps): the envelope of the first
// 1e4 (2.3e-2, the GVI notes' figure measured with deli: a regression pin) is never left,
// and the error has no trend (the paper's claim).
// Under the sanitizers (support/short_runs.hpp) the first 1e4 steps: the envelope and no
// overlap hold over them as over the whole run; the trend is the plain pass's.
TEST(PaperExamples, PogoStickBoundedTo1e5) {
  const Trace t = run_example("pogo_stick", testing::steps_or_prefix<std::int64_t>(-1, 10000), 1);
  std::printf("pogo: max |dE|/E0 %.3e, trend/fluctuation %.3f\n", t.max_relative_energy_error(),
              t.trend().ratio());
  EXPECT_LT(t.max_relative_energy_error(), 0.025);
  EXPECT_TRUE(no_overlap(t));
  if (testing::short_runs()) return;
  EXPECT_LT(t.trend().ratio(), kBounded);
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// The cradle's pattern: after the two pulled balls strike, the two on the far side leave
// and the rest come (nearly) to rest.
TEST(PaperExamples, NewtonsCradlePattern) {
  RunInput input =
      load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/paper/newtons_cradle_h0.005.toml");
  Gvi gvi(*input.force_field, input.constraints, input.gvi, input.system.particles);
  run(input.system, gvi, 130, 0, {});  // t = 0.65: after the strike, before the far balls return
  const Particles& p = input.system.particles;
  const double speed = norm(p.velocity[4]);
  std::printf("cradle at t = 0.65: |v| = %.3f %.3f %.3f %.3f %.3f\n", norm(p.velocity[0]),
              norm(p.velocity[1]), norm(p.velocity[2]), norm(p.velocity[3]), speed);
  EXPECT_GT(speed, 1.0);
  EXPECT_GT(norm(p.velocity[3]), 0.5 * speed);
  EXPECT_GT(p.velocity[4].x, 0.0);
  for (int k = 0; k < 3; ++k) EXPECT_LT(norm(p.velocity[k]), 0.2 * speed) << "ball " << k + 1;
}

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// The paper's LJ chain to 2000 time units: rods exact, no overlap, angular momentum
// exact, energy without trend (the paper's claims). The envelope bound is a regression
// pin (deli measured 0.14 then 0.21 of |E0| in the two halves).
TEST(PaperExamples, LjChainTo2000) {
  const Trace t = run_example("lj_chain", -1, 100);
  std::printf("LJ chain: max |dE|/|E0| %.3e, trend/fluctuation %.3f, |dL| %.3e\n",
              t.max_relative_energy_error(), t.trend().ratio(), t.max_angular_change());
  EXPECT_LT(t.max_relative_energy_error(), 0.3);
  EXPECT_LT(t.trend().ratio(), kBounded);
  EXPECT_LT(t.max_angular_change(), 1e-11);
  EXPECT_TRUE(no_overlap(t));
}

}  // namespace
}  // namespace deli
