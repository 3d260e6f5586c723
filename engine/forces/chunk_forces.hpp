#pragma once

#include <cstddef>
#include <type_traits>
#include <vector>

#include "core/parallel.hpp"
#include "core/vec3.hpp"

namespace deli {

// The chunked loop of a force term whose items (a particle's listed pairs, bonds, angles,
// dihedrals) also push particles outside their own chunk. Chunk 0 adds to the caller's
// force array and virial, chunk c > 0 to a force buffer and a virial of its own; after the
// chunks the buffers are added in chunk order, particle by particle, then the chunks'
// virials and energies, in chunk order too. One chunk is the serial loop, bit for bit; a
// given number of chunks adds in one fixed order: the same result on every run.
// The buffers are kept between calls (their memory reused). Not thread-safe across calls:
// one term's compute() at a time, as the force field does. Force: the force array's element
// (Vec3, or a padded form for vector loops), value-initialised to zero, with +=.
template <class Force>
class ChunkedForceLoopOf {
 public:
  // Runs body(begin, end, f, w) -> energy over the chunks of [0, items): the chunk's
  // items add their forces to f[particle] and their virial to w, and it returns their
  // energy. Returns the sum of the energies; forces added to `force`, virial to `virial`.
  // A body taking the chunk's number first, body(c, begin, end, f, w), is given it.
  template <class Body>
  double run(std::size_t items, std::vector<Force>& force, SymTensor& virial, Body&& body) {
    return run(items, force, virial, body, [](std::size_t) {});
  }
  // run(), then finish(i) for every particle i once its force is complete, in the pass that
  // adds the buffers (one parallel region and one pass over the forces fewer than a loop of
  // its own after run()).
  template <class Body, class Finish>
  double run(std::size_t items, std::vector<Force>& force, SymTensor& virial, Body&& body,
             Finish&& finish) {
    const int chunks = chunks_for(items);
    const auto extra = static_cast<std::size_t>(chunks - 1);
    buffers_.resize(extra);
    virials_.resize(extra);
    energies_.resize(static_cast<std::size_t>(chunks));
    // Equal chunks whatever the threads' speeds: the buffers' sums are grouped by chunk.
    for_each_fixed_chunk(items, chunks, [&](int c, std::size_t begin, std::size_t end) {
      const auto k = static_cast<std::size_t>(c);
      auto chunk = [&](Force* f, SymTensor& w) {
        if constexpr (std::is_invocable_v<Body&, int, std::size_t, std::size_t, Force*,
                                          SymTensor&>) {
          return body(c, begin, end, f, w);
        } else {
          return body(begin, end, f, w);
        }
      };
      if (c == 0) {
        energies_[0] = chunk(force.data(), virial);
        return;
      }
      // Zeroed by the thread that fills it (its first touch, on a many-socket machine).
      std::vector<Force>& buffer = buffers_[k - 1];
      buffer.assign(force.size(), Force{});
      virials_[k - 1] = SymTensor{};
      energies_[k] = chunk(buffer.data(), virials_[k - 1]);
    });
    if (extra == 0) {
      parallel_for(force.size(), finish);
      return energies_[0];
    }
    parallel_for(force.size(), [&](std::size_t i) {
      for (const std::vector<Force>& b : buffers_) force[i] += b[i];
      finish(i);
    });
    double energy = energies_[0];
    for (std::size_t c = 1; c < energies_.size(); ++c) {
      energy += energies_[c];
      virial += virials_[c - 1];
    }
    return energy;
  }

 private:
  std::vector<std::vector<Force>> buffers_;  // chunks 1.. : their forces
  std::vector<SymTensor> virials_;           // chunks 1.. : their virials
  std::vector<double> energies_;             // every chunk's energy
};
using ChunkedForceLoop = ChunkedForceLoopOf<Vec3>;

}  // namespace deli
