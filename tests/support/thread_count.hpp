#pragma once

#include <cstddef>
#include <cstdlib>

#include "core/parallel.hpp"

namespace deli::testing {

// The tests' waiting threads sleep (OMP_WAIT_POLICY=passive, unless set), as the CLI runs of
// the thread tests ask: ctest -j2 runs two tests on the CI machine's two cores, and spinning
// threads took the core the other test needed and lost theirs to it (ThreadsGvi 21 s beside
// the Layers tests' compilations in a CI run, 0.5 s alone; beside two busy loops 24 s against
// 1.7 s passive). Set before main, ahead of the team's first look at the policy.
inline const bool kTestsWaitPassively = ::setenv("OMP_WAIT_POLICY", "passive", 0) == 0;

// Sets the thread count for a scope (the tests run with OMP_NUM_THREADS=1), and splits the
// loops of cheap items and the cluster loops in chunks of half kParallelMinimum items (rows),
// so that 2 threads split them from kParallelMinimum on, as the others: these tests are about
// the split paths' results on systems of a thousand particles or rods, whatever the default
// cheap_chunk_minimum() and cluster_chunk_minimum().
class ThreadCount {
 public:
  explicit ThreadCount(int n)
      : before_(thread_count()),
        cheap_before_(cheap_chunk_minimum()),
        cluster_before_(cluster_chunk_minimum()) {
    set_thread_count(n);
    set_cheap_chunk_minimum(kParallelMinimum / 2);
    set_cluster_chunk_minimum(kParallelMinimum / 2);
  }
  ~ThreadCount() {
    set_thread_count(before_);
    set_cheap_chunk_minimum(cheap_before_);
    set_cluster_chunk_minimum(cluster_before_);
  }
  ThreadCount(const ThreadCount&) = delete;
  ThreadCount& operator=(const ThreadCount&) = delete;

 private:
  int before_;
  std::size_t cheap_before_, cluster_before_;
};

#ifdef _OPENMP
inline constexpr bool kThreaded = true;
#else
inline constexpr bool kThreaded = false;
#endif

}  // namespace deli::testing
