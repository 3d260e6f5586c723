#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <utility>
#include <vector>

#include "core/cache_line.hpp"

namespace deli {

// The shares of a loop's work for its chunks (one per thread) that follow the speeds its
// threads showed: for loops whose result does not depend on where the chunks are cut (each
// chunk's output joined in chunk order is the serial loop's), never for sums. On a machine
// whose vCPUs ran 20-30 % apart for whole runs (a host's other tenants), equal shares left
// the faster thread waiting for the other at every call (bench/README.md, "Stop 68").
class SpeedShares {
 public:
  // The shares for `chunks` chunks (summing to 1): the fixed ones where set for as many
  // chunks; else moved halfway from the last shares to each chunk's share of the speeds
  // (work a second) recorded since the last call, none below half an equal share (a thread
  // stalled for a moment is not left idle for long), or kept where a chunk recorded nothing
  // (equal at first). Restarts the recording.
  const std::vector<double>& update(int chunks) {
    const auto k = static_cast<std::size_t>(chunks);
    if (fixed_.size() == k) {
      shares_ = fixed_;
    } else {
      const double equal = 1.0 / static_cast<double>(k);
      if (shares_.size() != k) shares_.assign(k, equal);
      bool measured = recorded_.size() == k;
      double speeds = 0.0;
      for (std::size_t c = 0; measured && c < k; ++c) {
        const Recorded& r = recorded_[c].value;
        measured = r.seconds > 0.0 && r.work > 0.0;
        if (measured) speeds += r.work / r.seconds;
      }
      if (measured) {
        // Halfway (summing to 1, as both do), then drawn towards equal shares as far as
        // keeps every one at half an equal share or more.
        double towards = 1.0;
        for (std::size_t c = 0; c < k; ++c) {
          const Recorded& r = recorded_[c].value;
          shares_[c] = 0.5 * (shares_[c] + r.work / r.seconds / speeds);
          if (shares_[c] < 0.5 * equal) {
            towards = std::min(towards, 0.5 * equal / (equal - shares_[c]));
          }
        }
        for (double& s : shares_) s = equal + towards * (s - equal);
      }
    }
    recorded_.assign(k, {});
    return shares_;
  }
  // Chunk c did `work` units in `seconds` (by chunk c's thread: each chunk on its own line).
  // Ignored for a chunk beyond the last update's.
  void record(int chunk, double work, double seconds) {
    const auto c = static_cast<std::size_t>(chunk);
    if (c >= recorded_.size()) return;
    recorded_[c].value.work += work;
    recorded_[c].value.seconds += seconds;
  }
  // Shares fixed at `weights` over their sum for loops of as many chunks (tests: the results
  // are the same whatever the shares); empty: measured again.
  void fix(std::vector<double> weights) {
    double sum = 0.0;
    for (const double w : weights) sum += w;
    for (double& w : weights) w /= sum;
    fixed_ = std::move(weights);
  }

 private:
  struct Recorded {
    double work = 0.0;
    double seconds = 0.0;
  };
  std::vector<double> shares_, fixed_;
  std::vector<OnItsOwnLine<Recorded>> recorded_;
};

// Times a chunk's work for SpeedShares::record: seconds since it was made.
class ChunkClock {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  }

 private:
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace deli
