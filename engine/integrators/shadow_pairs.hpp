#pragma once

#include <cstdint>
#include <vector>

#include "forces/force_term.hpp"
#include "integrators/reflection.hpp"

namespace deli {

// The shadow operators' pairs (ShadowOperator::pairs) of every reflected cluster, made from
// the pair Hessian blocks touching them in one job over the blocks: block k goes to the
// cluster of each of its particles (once where both are in one), as a pair in that cluster's
// numbering with the cluster's particle first (the block is symmetric) and, where the other
// lies outside, that particle; each cluster's pairs in block order, as a scan of the blocks
// for that cluster alone gives them. In two passes with a barrier between: each chunk of
// blocks counts its pairs per cluster, then writes them where the counts of the clusters and
// chunks before it end. The same pairs on any number of threads.
class ShadowPairs {
 public:
  // cluster_of[p]: particle p's reflected cluster (0 .. clusters - 1), or -1; local_index[p]:
  // its index within that cluster. The blocks as pieces (the pair terms' chunks, read in
  // order), or as one vector; the pairs point into them.
  void make(const PairHessianPieces& blocks, const std::int32_t* cluster_of,
            const std::int32_t* local_index, std::size_t clusters);
  void make(const std::vector<PairHessian>& blocks, const std::int32_t* cluster_of,
            const std::int32_t* local_index, std::size_t clusters);
  const ShadowOperator::LocalPair* pairs(std::size_t cluster) const {
    return pairs_.data() + begin_[cluster];
  }
  std::size_t count(std::size_t cluster) const { return count_[cluster]; }

 private:
  struct Span {
    const PairHessian* blocks;
    std::size_t count;
  };
  void make(const std::int32_t* cluster_of, const std::int32_t* local_index, std::size_t clusters);

  std::vector<Span> spans_;                                // the blocks, piece by piece
  std::vector<std::vector<std::size_t>> counts_of_chunk_;  // [chunk][cluster]
  std::vector<ShadowOperator::LocalPair> pairs_;           // cluster by cluster
  std::vector<std::size_t> begin_, count_;
};

}  // namespace deli
