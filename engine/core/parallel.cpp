#include "core/parallel.hpp"

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/cpu_quota.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace deli {

namespace {
std::size_t cheap_chunk = 512;
std::size_t cluster_chunk = 256;
}  // namespace

std::size_t cluster_chunk_minimum() {
  return cluster_chunk;
}

void set_cluster_chunk_minimum(std::size_t n) {
  cluster_chunk = n;
}

std::size_t cheap_chunk_minimum() {
  return cheap_chunk;
}

void set_cheap_chunk_minimum(std::size_t n) {
  cheap_chunk = n;
}

int thread_count() {
#ifdef _OPENMP
  return std::max(1, omp_get_max_threads());
#else
  return 1;
#endif
}

void set_thread_count(int n) {
  if (n < 1) throw std::invalid_argument("thread count " + std::to_string(n) + " is below 1");
#ifdef _OPENMP
  omp_set_num_threads(n);
#else
  if (n > 1) {
    throw std::invalid_argument("this deli was built without OpenMP: it runs on one thread only");
  }
#endif
}

int use_default_thread_count() {
  const char* asked = std::getenv("OMP_NUM_THREADS");
  if (asked && *asked) return 0;
  const std::optional<int> quota = quota_cpus();
  if (!quota) return 0;
  const int cpus = std::min(cpus_available(), *quota);
  if (thread_count() <= cpus) return 0;
  set_thread_count(cpus);
  return cpus;
}

}  // namespace deli
