#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "constraints/constraint_set.hpp"
#include "constraints/row_stretches.hpp"
#include "core/range_pass.hpp"

namespace deli {

// ConstraintSet::nearby_inequalities (without linearisation), the same rows in the same
// order, from a short list kept between calls: the neighbour list's hard-sphere pairs (not
// bonded) within contact + margin at the positions where the short list was made. A pair
// within contact + reach at q was within contact + reach + 2 s of its anchor positions, s the
// largest displacement since: the short list serves while reach + 2 s <= margin and the
// neighbour list is the one it was made from; otherwise it is made again. The neighbour
// list reaches a force cutoff (LJ 2.5 + skin) far beyond contact: the short list holds a
// fraction of its pairs, and no bonded-pair search is left per call. Each short-list pair
// keeps its gap at the anchor positions: by the triangle inequality its gap at q is at least
// that less the two particles' displacements since, so a pair whose bound already exceeds
// the reach is passed over without reading its positions (in the hard-sphere fluid, whose
// list reaches contact + skin, the short list holds every list pair and most are so passed).
class NearbyRows {
 public:
  explicit NearbyRows(double margin = 0.5) : margin_(margin) {}
  // The rows into `out` and their gaps at q into `gap_at_q`: evaluate()'s, bit for bit,
  // where the gap may be at most `exact_below`; elsewhere it can be +infinity (a pair whose
  // squared distance alone shows it beyond, by far more than rounding). A row is kept when
  // its gap is at most `reach`, or, given `particle_reach` (one per particle, each at most
  // reach / 2), at most its two particles' reaches summed (a wall row: twice its particle's).
  // Given `make_reaches`, particle_reach is made by make_reaches(begin, end), chunk by chunk
  // as the particle passes split the particles, before anything reads it: in the job of the
  // collection's own first pass over the particles, when it runs one.
  // Given `stretches`, the rows are those of `stretches` after the call: where the hard-sphere
  // pairs were screened in chunks (and no wall adds rows after them), chunk 0's in `out` and
  // the others' left where their threads wrote them, borrowed until the next call; else
  // `out` alone.
  // Given `anchored_largest2`, the caller's own pass over the particles has written, into
  // anchors_for()'s buffer, each particle's |q - anchor| plus its reach (particle_reach), the
  // largest |q - anchor|^2 being *anchored_largest2: the collection then runs no pass over the
  // particles of its own (unless the short list is made again).
  // Given `then`, where the rows are left as `stretches` by the threads that screened them
  // (returns true): then(s, rows, gaps, count) for each stretch s, with its rows and gaps, on
  // that thread in the same job, right after it screened them.
  using StretchPass = std::function<void(int stretch, const Constraint* rows, const double* gaps,
                                         std::size_t count)>;
  bool collect(const ConstraintSet& set, const Particles& particles, const Vec3* q,
               const NeighborList& list, const Box& box, double reach, const double* particle_reach,
               double exact_below, std::vector<Constraint>& out, std::vector<double>& gap_at_q,
               const RangePass* make_reaches = nullptr, RowStretches* stretches = nullptr,
               const double* anchored_largest2 = nullptr, const StretchPass* then = nullptr);
  // Where the short list is the one made from `list` as now built, for `particle_count`
  // particles: its anchor positions, and the buffer for their displacements that a pass of
  // the caller may fill (see collect()). Else nulls: the next collection makes it again.
  struct Anchors {
    const Vec3* anchor = nullptr;
    double* moved = nullptr;
  };
  Anchors anchors_for(const NeighborList& list, std::size_t particle_count);

 private:
  // The short list at q; each particle's displacement since (moved_) starts at its reach
  // (zero without particle reaches). `make_reaches`, where given, makes the reaches first:
  // each chunk's, in the scan's job (its own job a build, before).
  void make(const ConstraintSet& set, const Particles& particles, const Vec3* q,
            const NeighborList& list, const Box& box, const double* particle_reach,
            const RangePass* make_reaches);

  // ConstraintSet::unconstrained_pairs by first particle (a particle has a bond or two, so
  // a short scan instead of a binary search over all bonds, whose branches mispredict).
  void index_bonded_pairs(const ConstraintSet& set, std::size_t particle_count);
  bool bonded(std::int32_t a, std::int32_t b) const;

  double margin_;
  // a < b, in the neighbour list's order, with a lower bound on their gap at the anchor
  // positions (in single precision, rounded down: a first screen may pass more pairs, never
  // fewer) and, when the list has image codes, the code of the list's periodic shift for
  // q_i - q_j, negated when a is the list's partner j (then q_a - q_b - shift is their
  // separation). Contact distances are the radii's sums, made again where needed. 16 bytes a
  // pair: the screen's second pass reads the pairs its first leaves in no order, one line of
  // memory each (with the shift and contact kept, 48 bytes a pair, that pass was 40 % of
  // screen_pairs' samples in the 32000-sphere fluid).
  struct Pair {
    std::int32_t a, b;
    float anchor_gap;
    std::uint8_t code;
    bool negated;
  };
  // The short list as make()'s chunks of the list's particles scanned it, each chunk's pairs
  // kept where its thread wrote them and screened there (joined in chunk order, they are the
  // serial scan's). Joined by the calling thread, the other threads' pairs crossed to its
  // core at every make, and back at every screen.
  struct ScannedChunk {
    std::vector<Pair> pairs;
    std::vector<std::int32_t> near;  // pairs that may be within reach, by index
    std::vector<double> near_d2;     // their squared distances at q, after the second screen
  };
  std::vector<ScannedChunk> scanned_;
  // make()'s chunks of the listed particles, and their listed pairs' running count.
  std::vector<std::size_t> scan_starts_, scan_offsets_;
  // Entries of one owner scan_list() tests at a time (its buffers on the stack).
  static constexpr std::size_t kScanBlock = 64;
  // The list's pairs of particles [first, last) within contact + margin at q, appended.
  void scan_list(const NeighborList::PartnerRanges& ranges, const Vec3* q, const Box& box,
                 const double* radius, bool bonded_pairs, std::size_t first, std::size_t last,
                 std::vector<Pair>& pairs) const;
  // The screen of the scanned chunk's pairs [first, last), their scratch at the same indices.
  void screen_pairs(ScannedChunk& chunk, const Vec3* q, const Box& box, const double* radius,
                    double reach, const double* particle_reach, double exact_below, double beyond,
                    std::size_t first, std::size_t last, std::vector<Constraint>& out,
                    std::vector<double>& gap_at_q) const;
  // Screen chunks 1.. of collect() (chunk 0 writes in place).
  std::vector<std::vector<Constraint>> chunk_rows_;
  std::vector<std::vector<double>> chunk_gaps_;
  // collect()'s particles within reach of each wall, with their gaps, per chunk of
  // particles: [chunk][wall].
  struct WallGap {
    std::int32_t particle;
    double gap;
  };
  std::vector<std::vector<std::vector<WallGap>>> wall_passing_;
  bool shifted_ = false;
  std::array<Vec3, 27> shifts_{};  // the list's image shifts by code
  bool one_radius_ = false;        // every particle's radius the same:
  double one_contact_ = 0.0;       // then every pair's contact distance
  std::vector<Vec3> anchor_;
  std::vector<double> moved_;  // per particle, |q - anchor| at the last call (+ its reach)
  const NeighborList* list_ = nullptr;
  std::int64_t list_builds_ = -1;
  std::vector<std::int32_t> bonded_first_, bonded_partner_;
  const void* bonded_source_ = nullptr;
  std::size_t bonded_count_ = 0;
};

}  // namespace deli
