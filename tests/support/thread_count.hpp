#pragma once

#include <cstddef>

#include "core/parallel.hpp"

namespace deli::testing {

// Sets the thread count for a scope (the tests run with OMP_NUM_THREADS=1), and splits the
// loops of cheap items and the cluster loops from kParallelMinimum items (rows) on, as the
// others: the systems of the tests (a few thousand particles, about a thousand rods) are below
// the default cheap_loop_minimum() and cluster_work_minimum(), and these tests are about the
// split paths' results.
class ThreadCount {
 public:
  explicit ThreadCount(int n)
      : before_(thread_count()),
        cheap_before_(cheap_loop_minimum()),
        cluster_before_(cluster_work_minimum()) {
    set_thread_count(n);
    set_cheap_loop_minimum(kParallelMinimum);
    set_cluster_work_minimum(kParallelMinimum);
  }
  ~ThreadCount() {
    set_thread_count(before_);
    set_cheap_loop_minimum(cheap_before_);
    set_cluster_work_minimum(cluster_before_);
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
