#pragma once

#include <cstddef>

#include "core/parallel.hpp"

namespace deli::testing {

// Sets the thread count for a scope (the tests run with OMP_NUM_THREADS=1), and splits the
// loops of cheap items from kParallelMinimum items on, as the others: the systems of the
// tests (a few thousand particles) are below the default cheap_loop_minimum(), and these
// tests are about the split paths' results.
class ThreadCount {
 public:
  explicit ThreadCount(int n) : before_(thread_count()), cheap_before_(cheap_loop_minimum()) {
    set_thread_count(n);
    set_cheap_loop_minimum(kParallelMinimum);
  }
  ~ThreadCount() {
    set_thread_count(before_);
    set_cheap_loop_minimum(cheap_before_);
  }
  ThreadCount(const ThreadCount&) = delete;
  ThreadCount& operator=(const ThreadCount&) = delete;

 private:
  int before_;
  std::size_t cheap_before_;
};

#ifdef _OPENMP
inline constexpr bool kThreaded = true;
#else
inline constexpr bool kThreaded = false;
#endif

}  // namespace deli::testing
