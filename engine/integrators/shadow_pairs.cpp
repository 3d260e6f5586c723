#include "integrators/shadow_pairs.hpp"

#include <algorithm>

#include "core/parallel.hpp"

namespace deli {

void ShadowPairs::make(const std::vector<PairHessian>& blocks, const std::int32_t* cluster_of,
                       const std::int32_t* local_index, std::size_t clusters) {
  const std::size_t n = blocks.size();
  const int chunks = chunks_for_cheap(n);
  counts_of_chunk_.resize(static_cast<std::size_t>(std::max(chunks, 1)));
  for (std::vector<std::size_t>& counts : counts_of_chunk_) counts.assign(clusters, 0);
  // A block makes a pair for each of its two particles' clusters at most. Grown, never cut:
  // what lies past the pairs made is not read.
  if (pairs_.size() < 2 * n) pairs_.resize(2 * n);
  begin_.assign(clusters, 0);
  count_.assign(clusters, 0);
  const PairHessian* block = blocks.data();
  ShadowOperator::LocalPair* out = pairs_.data();
  auto count_pairs = [&, block, cluster_of](int chunk, std::size_t begin, std::size_t end) {
    std::size_t* counts = counts_of_chunk_[static_cast<std::size_t>(chunk)].data();
    for (std::size_t k = begin; k < end; ++k) {
      const std::int32_t a = cluster_of[block[k].a], b = cluster_of[block[k].b];
      if (a >= 0) ++counts[a];
      if (b >= 0 && b != a) ++counts[b];
    }
  };
  auto write_pairs = [&, block, cluster_of, local_index, out](int chunk, std::size_t begin,
                                                              std::size_t end) {
    const auto own = static_cast<std::size_t>(chunk);
    // Where this chunk's pairs of each cluster go.
    thread_local std::vector<std::size_t> at;
    at.assign(clusters, 0);
    std::size_t start = 0;
    for (std::size_t r = 0; r < clusters; ++r) {
      std::size_t total = 0;
      for (std::size_t c = 0; c < counts_of_chunk_.size(); ++c) {
        if (c == own) at[r] = start + total;
        total += counts_of_chunk_[c][r];
      }
      if (own == 0) begin_[r] = start, count_[r] = total;
      start += total;
    }
    for (std::size_t k = begin; k < end; ++k) {
      const PairHessian& b = block[k];
      const std::int32_t ca = cluster_of[b.a], cb = cluster_of[b.b];
      if (ca >= 0) {
        out[at[ca]++] = cb == ca
                            ? ShadowOperator::LocalPair{local_index[b.a], local_index[b.b], -1, k}
                            : ShadowOperator::LocalPair{local_index[b.a], -1, b.b, k};
      }
      if (cb >= 0 && cb != ca) {
        out[at[cb]++] = ShadowOperator::LocalPair{local_index[b.b], -1, b.a, k};
      }
    }
  };
  for_each_chunk_then(n, n, chunks, count_pairs, write_pairs);
}

}  // namespace deli
