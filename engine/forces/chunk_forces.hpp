#pragma once

#include <cstddef>
#include <vector>

#include "core/parallel.hpp"
#include "core/vec3.hpp"

namespace deli {

// Force accumulators for a term whose items (a particle's listed pairs, bonds, angles) also
// push particles outside their own chunk. Chunk 0 adds to the force array itself, chunk
// c > 0 to a buffer of its own; add_buffers() then adds the buffers in chunk order,
// particle by particle. One chunk writes straight into the force array: the serial loop.
// Not thread-safe across calls: one term's compute() at a time, as the force field does.
class ChunkForces {
 public:
  // Before the chunks run: room for `chunks` of n particles.
  void prepare(int chunks, std::size_t n) {
    buffers_.resize(static_cast<std::size_t>(chunks > 1 ? chunks - 1 : 0));
    size_ = n;
  }
  // Inside chunk c: where it adds its forces (a zeroed buffer for c > 0, zeroed by the
  // thread that uses it).
  Vec3* chunk(int c, std::vector<Vec3>& force) {
    if (c == 0) return force.data();
    std::vector<Vec3>& b = buffers_[static_cast<std::size_t>(c - 1)];
    b.assign(size_, Vec3{});
    return b.data();
  }
  // After the chunks: force[i] += buffer_1[i], then buffer_2[i], ...
  void add_buffers(std::vector<Vec3>& force) const {
    if (buffers_.empty()) return;
    parallel_for(size_, [&](std::size_t i) {
      for (const std::vector<Vec3>& b : buffers_) force[i] += b[i];
    });
  }

 private:
  std::vector<std::vector<Vec3>> buffers_;
  std::size_t size_ = 0;
};

}  // namespace deli
