// Two thread counts' speeds on one input, measured in one process in alternating bursts of
// steps (not a test): the ratio bench/threads.sh reports (two threads over one), with the
// machine's drift shared by both counts, and the machine's ceiling measured in the same
// rounds. On the shared virtual machines deli is benchmarked on, one-thread runs of one binary
// moved up to 30 % apart within minutes, and the ratio of whole runs (bench/threads.sh
// alternates processes) read from 1.3x to 1.8x for the same code within one session. Here
// each round runs a burst of each kind: A threads, B threads, and (A = 1) B one-thread copies
// of the input at once, in turn and then the other way round (A B C, C B A, ...: a drift
// within a round falls on every kind alike). The ratio is the kinds' summed loop times', beside
// the spread of the rounds' own ratios, the fraction of the ceiling reached and the ratio
// phase by phase. Each count, and each copy, runs its own copy of the input from the input's
// start (its bursts one run of it, a step per step of every burst); the set-up and a first
// burst of each kind are not timed, each burst follows a tenth as many untimed steps (Runner),
// and the input's outputs (thermo, trajectory) are not written.
//   cmake --build build --target deli-interleaved-threads
//   build/bench/interleaved_threads/deli-interleaved-threads INPUT.toml [ROUNDS [STEPS [A B]]]
// ROUNDS (default 10): bursts of each kind; STEPS (default 1000): steps a burst (a few tenths
// of a second at least); A and B (default 1 and 2): the thread counts.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.hpp"
#include "cli/integrator_factory.hpp"
#include "core/parallel.hpp"
#include "core/phase_timer.hpp"
#include "core/thread_team.hpp"
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

// The input loaded as `deli run` loads it, refused where it asks for a minimisation first.
RunInput load(const std::string& path) {
  RunInput input = load_run_input(path);
  if (input.minimize.max_steps != 0) {
    throw std::invalid_argument(path +
                                ": asks for a minimisation first ([minimize]); measure the "
                                "input it writes, or one without [minimize]");
  }
  return input;
}

// An input's system and integrator on a thread count of its own, run in bursts of steps.
// Each count runs its own copy of the input: an integrator's workspaces are split for the
// count it was set up with (the contact search's stretches, one per thread), which a run does
// not change, and one made anew at each change of count would start each burst cold.
class Runner {
 public:
  Runner(const std::string& path, int threads) : input_(load(path)), threads_(threads) {
    options_.degrees_of_freedom = input_.degrees_of_freedom;
    options_.start_temperature = input_.start_temperature;
  }
  // Runs `steps` steps; the count is set for the calling thread (OpenMP's setting is each
  // thread's own: a thread started by std::thread begins at the default count).
  // A tenth as many steps first, not timed: a worker that slept through the other kinds'
  // bursts is woken (possibly onto its waker's CPU, until the scheduler moves it) and spins
  // again, and the burst's lines are brought back to the cores, as in a run's steady state.
  Burst burst(long steps) {
    set_thread_count(threads_);
    if (!integrator_) integrator_ = make_integrator(input_);
    advance(std::max(1L, steps / 10));
    const RunStatistics stats = advance(steps);
    return Burst{stats.loop_seconds, stats.phase_seconds};
  }
  const RunInput& input() const { return input_; }

 private:
  RunStatistics advance(long steps) {
    const RunStatistics stats = run(input_.system, *integrator_, steps, 0, {}, options_);
    options_.set_up = false;
    options_.start_temperature.reset();
    return stats;
  }

  RunInput input_;
  int threads_;
  RunOptions options_;
  std::unique_ptr<Integrator> integrator_;
};

int measure(int argc, char** argv) {
  if (argc < 2 || argc > 6 || argc == 5) {
    std::fprintf(stderr, "usage: %s INPUT.toml [ROUNDS [STEPS [A B]]]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  const long rounds = argc > 2 ? parse_count(argv[2], "ROUNDS", 1) : 10;
  const long steps = argc > 3 ? parse_count(argv[3], "STEPS", 1) : 1000;
  const std::array<int, 2> counts{argc > 5 ? static_cast<int>(parse_count(argv[4], "A", 1)) : 1,
                                  argc > 5 ? static_cast<int>(parse_count(argv[5], "B", 1)) : 2};
  std::array<std::unique_ptr<Runner>, 2> runners{std::make_unique<Runner>(path, counts[0]),
                                                 std::make_unique<Runner>(path, counts[1])};
  const RunInput& input = runners[0]->input();
  apply_chunk_settings(input);
  // The machine's ceiling, with A = 1: B one-thread copies of the input at once, each on a
  // thread of its own (runners of their own: A's runner and B's advance alike, a step per step
  // of a burst, and reach the input's later stretches together), their rates summed, over
  // one alone. No code on B threads can beat it; cores that slow each other (shared caches, a
  // host's other tenants) put it below B.
  const bool ceiling = counts[0] == 1 && counts[1] > 1;
  std::vector<std::unique_ptr<Runner>> copies;
  if (ceiling) {
    for (int k = 0; k < counts[1]; ++k) copies.push_back(std::make_unique<Runner>(path, 1));
  }
  // A burst of every copy's at once, the first on this thread: each copy's loop time into
  // copy_seconds.
  auto copies_at_once = [&](std::vector<double>& copy_seconds) {
    std::vector<Burst> of_copy(copies.size());
    std::vector<std::exception_ptr> failed(copies.size());
    std::vector<std::thread> threads;
    for (std::size_t k = 1; k < copies.size(); ++k) {
      threads.emplace_back([&, k] {
        try {
          of_copy[k] = copies[k]->burst(steps);
        } catch (...) {
          failed[k] = std::current_exception();
        }
      });
    }
    try {
      of_copy[0] = copies[0]->burst(steps);
    } catch (...) {
      failed[0] = std::current_exception();
    }
    for (std::thread& t : threads) t.join();
    for (const std::exception_ptr& e : failed) {
      if (e) std::rethrow_exception(e);
    }
    for (const Burst& b : of_copy) copy_seconds.push_back(b.loop_seconds);
  };
  // The set-up, the team started, everything warm: not timed.
  for (const std::unique_ptr<Runner>& r : runners) r->burst(steps);
  std::vector<double> copy_seconds;  // per round, copies.size() of them in a row
  if (ceiling) copies_at_once(copy_seconds);
  copy_seconds.clear();
  // Kinds: A threads, B threads, the copies at once. Each kind's burst in turn, then the
  // other way round (A B C, C B A, ...): a drift within a round falls on every kind alike.
  const std::size_t kinds = ceiling ? 3 : 2;
  std::array<std::vector<Burst>, 2> bursts;
  for (long round = 0; round < rounds; ++round) {
    for (std::size_t k = 0; k < kinds; ++k) {
      const std::size_t kind = round % 2 == 0 ? k : kinds - 1 - k;
      if (kind == 2) {
        copies_at_once(copy_seconds);
      } else {
        bursts[kind].push_back(runners[kind]->burst(steps));
      }
    }
  }
  const std::size_t atoms = input.system.particles.size();
  std::printf("%s: %zu atoms, %ld rounds of bursts of %ld steps, %d and %d threads\n", path.c_str(),
              atoms, rounds, steps, counts[0], counts[1]);
  const double atom_steps = static_cast<double>(atoms) * static_cast<double>(steps * rounds);
  std::array<Burst, 2> total{};
  for (std::size_t c = 0; c < 2; ++c) {
    for (const Burst& b : bursts[c]) {
      total[c].loop_seconds += b.loop_seconds;
      for (std::size_t p = 0; p < phase_count; ++p) total[c].phase_seconds[p] += b.phase_seconds[p];
    }
    std::printf("  %d thread%s: %.4g atom-steps/s (loop %.3f s)\n", counts[c],
                counts[c] == 1 ? "" : "s", atom_steps / total[c].loop_seconds,
                total[c].loop_seconds);
  }
  std::vector<double> ratios;
  for (std::size_t k = 0; k < bursts[0].size(); ++k) {
    ratios.push_back(bursts[0][k].loop_seconds / bursts[1][k].loop_seconds);
  }
  const double scaling = total[0].loop_seconds / total[1].loop_seconds;
  std::printf(
      "  %d over %d threads: %.3fx (the summed loop times); rounds: median %.3fx, quartiles "
      "%.3fx and %.3fx, range %.3fx to %.3fx\n",
      counts[1], counts[0], scaling, quantile(ratios, 0.5), quantile(ratios, 0.25),
      quantile(ratios, 0.75), quantile(ratios, 0.0), quantile(ratios, 1.0));
  if (ceiling) {
    // Each copy's rate over its bursts' summed loop times.
    double rate = 0;
    for (std::size_t k = 0; k < copies.size(); ++k) {
      double seconds = 0;
      for (std::size_t b = k; b < copy_seconds.size(); b += copies.size()) {
        seconds += copy_seconds[b];
      }
      rate += atom_steps / seconds;
    }
    const double one = atom_steps / total[0].loop_seconds;
    std::printf(
        "  the machine's ceiling (%d one-thread copies at once, their rates summed, over one): "
        "%.3fx; %d threads reach %.0f %% of it\n",
        counts[1], rate / one, counts[1], 100.0 * scaling / (rate / one));
  }
  if (const long long spells = crowded_spells(); spells > 0) {
    std::printf(
        "  the team waited as passive %lld time%s (other threads crowded the CPUs: README, "
        "\"Threads and vector instructions\"); the figures above include those spells\n",
        spells, spells == 1 ? "" : "s");
  }
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
