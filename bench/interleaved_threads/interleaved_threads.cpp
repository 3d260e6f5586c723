// Two thread counts' speeds on one input, measured in one process in short alternating bursts
// of steps (not a test): the ratio bench/threads.sh reports (two threads over one), but
// with the machine's drift shared by both counts. On the shared virtual machines deli is
// benchmarked on, one-thread runs of one binary moved up to 30 % apart within minutes, and the
// ratio of two whole runs (bench/threads.sh alternates processes of a second or more) read
// anywhere from 1.3x to 1.8x for the same code within one session. Here the run is cut into
// bursts of a tenth of a second or so, the counts alternate burst by burst (A B B A ...: a
// drift within a pair of bursts falls on both alike), and the ratio is the two counts' summed
// loop times', beside the spread of the pairs' own ratios and the ratio phase by phase.
// A burst at another count continues as a restart does. Hard spheres and rods alone follow
// the input's one trajectory whatever the counts and bursts (README, "Threads and vector
// instructions"; the final sums printed say so); with pair forces each count regroups the
// sums, and the trajectory separates from a one-count run's in its last bits, as a run on
// another count does.
//   cmake --build build --target deli-interleaved-threads
//   build/bench/interleaved_threads/deli-interleaved-threads INPUT.toml [PAIRS [STEPS [A B]]]
// PAIRS (default 20): bursts at each count; STEPS (default 300): steps a burst; A and B
// (default 1 and 2): the thread counts. The set-up and a first burst at each count are not
// timed. Outputs of the input (thermo, trajectory) are not written.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/integrator_factory.hpp"
#include "core/chunk_balance.hpp"
#include "core/parallel.hpp"
#include "core/phase_timer.hpp"
#include "input/run_input.hpp"
#include "simulation/run_loop.hpp"

namespace deli {
namespace {

struct Burst {
  double loop_seconds = 0;
  std::array<double, phase_count> phase_seconds{};
};

long parse_count(const char* text, const char* what, long low) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (*text == '\0' || *end != '\0' || value < low) {
    throw std::invalid_argument(std::string(what) + " " + text +
                                ": expected an integer of at least " + std::to_string(low));
  }
  return value;
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto k = static_cast<std::size_t>(at);
  if (k + 1 >= v.size()) return v.back();
  return v[k] + (at - static_cast<double>(k)) * (v[k + 1] - v[k]);
}

int measure(int argc, char** argv) {
  if (argc < 2 || argc > 6 || argc == 5) {
    std::fprintf(stderr, "usage: %s INPUT.toml [PAIRS [STEPS [A B]]]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  const long pairs = argc > 2 ? parse_count(argv[2], "PAIRS", 1) : 20;
  const long steps = argc > 3 ? parse_count(argv[3], "STEPS", 1) : 300;
  const std::array<int, 2> counts{argc > 5 ? static_cast<int>(parse_count(argv[4], "A", 1)) : 1,
                                  argc > 5 ? static_cast<int>(parse_count(argv[5], "B", 1)) : 2};
  RunInput input = load_run_input(path);
  if (input.minimize.max_steps != 0) {
    throw std::invalid_argument(path +
                                ": asks for a minimisation first ([minimize]); measure the "
                                "input it writes, or one without [minimize]");
  }
  set_chunk_balance(input.balance_threads);
  if (!input.split_small_loops) {
    set_cheap_chunk_minimum(kUnsplitCheapChunk);
    set_cluster_chunk_minimum(kUnsplitClusterChunk);
  }
  std::unique_ptr<Integrator> integrator = make_integrator(input);
  RunOptions options;
  options.degrees_of_freedom = input.degrees_of_freedom;
  options.start_temperature = input.start_temperature;
  const std::vector<Observer*> none;
  // A burst at another count continues as a restart does, with an integrator made anew
  // (bit for bit the run's own trajectory): an integrator's workspaces are split for the count
  // it was set up with (the contact search's stretches, one per thread), which a run does not
  // change.
  int last_threads = 0;
  auto burst = [&](int threads) {
    if (last_threads != 0 && threads != last_threads) {
      const std::vector<double> state = integrator->saved_state();
      const std::vector<Vec3> build_positions =
          integrator->forces().neighbors().positions_at_build();
      integrator.reset();
      set_thread_count(threads);
      integrator = make_integrator(input);
      integrator->resume(input.system, build_positions, state);
    }
    set_thread_count(threads);
    last_threads = threads;
    const RunStatistics stats = run(input.system, *integrator, steps, 0, none, options);
    options.set_up = false;
    options.start_temperature.reset();
    return Burst{stats.loop_seconds, stats.phase_seconds};
  };
  for (const int threads : counts) burst(threads);  // the set-up, the team started, warm
  std::array<std::vector<Burst>, 2> bursts;
  for (long pair = 0; pair < pairs; ++pair) {
    for (int k = 0; k < 2; ++k) {
      const int which = pair % 2 == 0 ? k : 1 - k;  // A B, then B A
      bursts[static_cast<std::size_t>(which)].push_back(
          burst(counts[static_cast<std::size_t>(which)]));
    }
  }
  const std::size_t atoms = input.system.particles.size();
  // The trajectory is the same whichever counts and bursts ran it: these sums say so when two
  // invocations (other counts, other bursts, the same total steps) are compared.
  double position_sum = 0, velocity_sum = 0;
  for (std::size_t i = 0; i < atoms; ++i) {
    const Vec3& x = input.system.particles.position[i];
    const Vec3& v = input.system.particles.velocity[i];
    position_sum += x.x + x.y + x.z;
    velocity_sum += v.x + v.y + v.z;
  }
  std::printf("%s: %zu atoms, %ld pairs of bursts of %ld steps, %d and %d threads\n", path.c_str(),
              atoms, pairs, steps, counts[0], counts[1]);
  std::printf("  at step %lld: positions' sum %.17g, velocities' sum %.17g\n",
              static_cast<long long>(input.system.step), position_sum, velocity_sum);
  std::array<Burst, 2> total{};
  for (std::size_t c = 0; c < 2; ++c) {
    for (const Burst& b : bursts[c]) {
      total[c].loop_seconds += b.loop_seconds;
      for (std::size_t p = 0; p < phase_count; ++p) total[c].phase_seconds[p] += b.phase_seconds[p];
    }
    const double atom_steps = static_cast<double>(atoms) * static_cast<double>(steps * pairs);
    std::printf("  %d thread%s: %.4g atom-steps/s (loop %.3f s)\n", counts[c],
                counts[c] == 1 ? "" : "s", atom_steps / total[c].loop_seconds,
                total[c].loop_seconds);
  }
  std::vector<double> ratios;
  for (std::size_t k = 0; k < bursts[0].size(); ++k) {
    ratios.push_back(bursts[0][k].loop_seconds / bursts[1][k].loop_seconds);
  }
  std::printf(
      "  %d over %d threads: %.3fx (the summed loop times); pairs of bursts: median %.3fx, "
      "quartiles %.3fx and %.3fx, range %.3fx to %.3fx\n",
      counts[1], counts[0], total[0].loop_seconds / total[1].loop_seconds, quantile(ratios, 0.5),
      quantile(ratios, 0.25), quantile(ratios, 0.75), quantile(ratios, 0.0), quantile(ratios, 1.0));
  std::printf("  %-20s %10s %10s %8s\n", "phase", "A (s)", "B (s)", "A / B");
  for (std::size_t p = 0; p < phase_count; ++p) {
    const double a = total[0].phase_seconds[p], b = total[1].phase_seconds[p];
    if (a <= 0 && b <= 0) continue;
    std::printf("  %-20s %10.4f %10.4f %7.2fx\n", phase_name(static_cast<Phase>(p)), a, b,
                b > 0 ? a / b : 0.0);
  }
  return 0;
}

}  // namespace
}  // namespace deli

int main(int argc, char** argv) {
  try {
    return deli::measure(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "deli-interleaved-threads: %s\n", e.what());
    return 1;
  }
}
