#include "integrators/shadow_pairs.hpp"

#include <algorithm>

#include "core/parallel.hpp"

namespace deli {

namespace {

// body(block) for blocks [begin, end) of the spans' sequence, in order.
template <class Spans, class Body>
void for_each_block(const Spans& spans, std::size_t begin, std::size_t end, Body&& body) {
  std::size_t start = 0;
  for (const auto& span : spans) {
    const std::size_t from = std::max(begin, start), to = std::min(end, start + span.count);
    for (std::size_t k = from; k < to; ++k) body(span.blocks[k - start]);
    start += span.count;
    if (start >= end) break;
  }
}

}  // namespace

void ShadowPairs::make(const PairHessianPieces& blocks, const std::int32_t* cluster_of,
                       const std::int32_t* local_index, std::size_t clusters) {
  spans_.clear();
  for (std::size_t k = 0; k < blocks.used; ++k) {
    spans_.push_back({blocks.pieces[k].data(), blocks.pieces[k].size()});
  }
  make(cluster_of, local_index, clusters);
}

void ShadowPairs::make(const std::vector<PairHessian>& blocks, const std::int32_t* cluster_of,
                       const std::int32_t* local_index, std::size_t clusters) {
  spans_.assign(1, Span{blocks.data(), blocks.size()});
  make(cluster_of, local_index, clusters);
}

void ShadowPairs::make(const std::int32_t* cluster_of, const std::int32_t* local_index,
                       std::size_t clusters) {
  std::size_t n = 0;
  for (const Span& span : spans_) n += span.count;
  const int chunks = chunks_for_cheap(n);
  counts_of_chunk_.resize(static_cast<std::size_t>(std::max(chunks, 1)));
  for (std::vector<std::size_t>& counts : counts_of_chunk_) counts.assign(clusters, 0);
  // A block makes a pair for each of its two particles' clusters at most. Grown, never cut:
  // what lies past the pairs made is not read.
  if (pairs_.size() < 2 * n) pairs_.resize(2 * n);
  begin_.assign(clusters, 0);
  count_.assign(clusters, 0);
  ShadowOperator::LocalPair* out = pairs_.data();
  auto count_pairs = [&, cluster_of](int chunk, std::size_t begin, std::size_t end) {
    std::size_t* counts = counts_of_chunk_[static_cast<std::size_t>(chunk)].data();
    for_each_block(spans_, begin, end, [&](const PairHessian& block) {
      const std::int32_t a = cluster_of[block.a], b = cluster_of[block.b];
      if (a >= 0) ++counts[a];
      if (b >= 0 && b != a) ++counts[b];
    });
  };
  auto write_pairs = [&, cluster_of, local_index, out](int chunk, std::size_t begin,
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
    for_each_block(spans_, begin, end, [&](const PairHessian& b) {
      const std::int32_t ca = cluster_of[b.a], cb = cluster_of[b.b];
      if (ca >= 0) {
        out[at[ca]++] = cb == ca
                            ? ShadowOperator::LocalPair{local_index[b.a], local_index[b.b], -1, &b}
                            : ShadowOperator::LocalPair{local_index[b.a], -1, b.b, &b};
      }
      if (cb >= 0 && cb != ca) {
        out[at[cb]++] = ShadowOperator::LocalPair{local_index[b.b], -1, b.a, &b};
      }
    });
  };
  for_each_chunk_then(n, n, chunks, count_pairs, write_pairs);
}

}  // namespace deli
