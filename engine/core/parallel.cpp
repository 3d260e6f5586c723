#include "core/parallel.hpp"

#include <stdexcept>
#include <string>

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

}  // namespace deli
