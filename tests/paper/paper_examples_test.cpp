// The paper's examples (inputs/paper/) run to their stated lengths and show the paper's
// claims for GVI: bounded energy, exact angular momentum where it is conserved, no
// overlap, the cradle's energy error second order in h, linearised constraints losing
// the angular momentum the nonlinear ones keep.
#include <gtest/gtest.h>

#include <cmath>

#include "input/run_input.hpp"
#include "integrators/gvi.hpp"
#include "simulation/run_loop.hpp"

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
  // Largest error in the second half over the largest in the first: about 1 when bounded.
  double growth() const {
    const std::size_t half = energy.size() / 2;
    double first = 0, second = 0;
    for (std::size_t k = 0; k < energy.size(); ++k) {
      (k < half ? first : second) =
          std::max(k < half ? first : second, std::abs(energy[k] - energy.front()));
    }
    return second / std::max(first, 1e-300);
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

class Record final : public Observer {
 public:
  explicit Record(Trace& t) : t_(t) {}
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
  Record record(trace);
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
  std::printf("spring and sphere, smooth: max |dE|/E0 %.3e, growth %.2f, |dL| %.3e\n",
              t.max_relative_energy_error(), t.growth(), t.max_angular_change());
  EXPECT_LT(t.max_relative_energy_error(), 0.08);  // measured 6.7e-2 at h = 0.5
  EXPECT_LT(t.growth(), 1.2);
  EXPECT_LT(t.max_angular_change(), 1e-11 * std::abs(t.angular_z.front()));
  EXPECT_TRUE(no_overlap(t));
}

TEST(PaperExamples, SpringAndSphereMixed) {
  const Trace t = run_example("spring_sphere_mixed");
  std::printf("spring and sphere, mixed: max |dE|/E0 %.3e, growth %.2f, |dL| %.3e\n",
              t.max_relative_energy_error(), t.growth(), t.max_angular_change());
  EXPECT_LT(t.max_relative_energy_error(), 0.12);  // measured 9.9e-2 at h = 0.5
  EXPECT_LT(t.max_angular_change(), 1e-11 * std::abs(t.angular_z.front()));
  EXPECT_TRUE(no_overlap(t));
}

TEST(PaperExamples, NonlinearOscillatorKeepsAngularMomentumLinearisedLosesIt) {
  const Trace exact = run_example("nonlinear_oscillator");
  const Trace linear = run_example("nonlinear_oscillator_linearized");
  std::printf("oscillator: |dE|/E0 %.3e, |dL| %.3e; linearised: |dE|/E0 %.3e, |dL| %.3e\n",
              exact.max_relative_energy_error(), exact.max_angular_change(),
              linear.max_relative_energy_error(), linear.max_angular_change());
  EXPECT_LT(exact.max_relative_energy_error(), 0.03);  // measured 2.4e-2 (every step)
  EXPECT_LT(exact.growth(), 1.2);
  EXPECT_LT(exact.max_angular_change(), 1e-12 * std::abs(exact.angular_z.front()));
  EXPECT_LT(linear.max_relative_energy_error(), 0.03);  // energy still kept (2.6e-2)
  EXPECT_GT(linear.max_angular_change(), 0.1 * std::abs(linear.angular_z.front()));
}

// Energy error second order in h, stable across the sweep (20 time units each).
TEST(PaperExamples, NewtonsCradleSweep) {
  std::vector<double> errors;
  for (const char* h : {"0.03", "0.02", "0.01", "0.005"}) {
    const Trace t = run_example(std::string("newtons_cradle_h") + h);
    errors.push_back(t.max_relative_energy_error());
    EXPECT_LT(t.growth(), 1.5) << "h = " << h;
    EXPECT_TRUE(no_overlap(t)) << "h = " << h;
  }
  std::printf("cradle |dE|/|E0|: %.3e %.3e %.3e %.3e\n", errors[0], errors[1], errors[2],
              errors[3]);
  EXPECT_LT(errors[2], 5e-5);
  const double ratio = errors[2] / errors[3];
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.0);
}

// The pogo stick to the paper's 1e5 time units (1e6 steps): the envelope of the first
// 1e4 (2.3e-2, the notes' figure) is never left.
TEST(PaperExamples, PogoStickBoundedTo1e5) {
  const Trace t = run_example("pogo_stick", -1, 1);
  std::printf("pogo: max |dE|/E0 %.3e, growth %.2f\n", t.max_relative_energy_error(), t.growth());
  EXPECT_LT(t.max_relative_energy_error(), 0.025);
  EXPECT_LT(t.growth(), 1.05);
  EXPECT_TRUE(no_overlap(t));
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
// exact, energy within the band of the first half (measured 0.14 then 0.21 of |E0|).
TEST(PaperExamples, LjChainTo2000) {
  const Trace t = run_example("lj_chain", -1, 100);
  std::printf("LJ chain: max |dE|/|E0| %.3e, growth %.2f, |dL| %.3e\n",
              t.max_relative_energy_error(), t.growth(), t.max_angular_change());
  EXPECT_LT(t.max_relative_energy_error(), 0.3);
  EXPECT_LT(t.growth(), 2.0);
  EXPECT_LT(t.max_angular_change(), 1e-11);
  EXPECT_TRUE(no_overlap(t));
}

}  // namespace
}  // namespace deli
