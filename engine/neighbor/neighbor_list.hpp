#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

#include "core/vec3.hpp"
#include "neighbor/touched_blocks.hpp"
#include "system/box.hpp"

namespace deli {

// Half Verlet list (each pair once, under either of its particles) built through a cell
// list, with the pairs whose minimum-image distance is below cutoff + skin; pairs in
// `excluded` never appear. It stays valid until some particle has moved more than skin/2
// since the build: no pair can then have closed from beyond cutoff + skin to within the
// cutoff. The list depends only on the positions (cell order, then particle order within a
// cell), so results are deterministic.
class NeighborList {
 public:
  NeighborList(double cutoff, double skin);

  double cutoff() const { return cutoff_; }
  double skin() const { return skin_; }

  // Pairs to leave out (bonded exclusions), in any order.
  void set_exclusions(std::vector<std::array<std::int32_t, 2>> excluded);

  void build(const std::vector<Vec3>& position, const Box& box) { build(position, box, nullptr); }
  // A caller's pass over each chunk of the particles, run in the build's first job just before
  // the build reads the chunk's positions (the force engine's check and wrap of them: a job
  // and a read of the positions fewer a build). It returns false where the chunk's particles
  // cannot be listed (a non-finite position): then build stops after that job, returns false
  // and leaves no list (built_for() is false until a build completes).
  using ChunkCheck = std::function<bool(std::size_t begin, std::size_t end)>;
  bool build(const std::vector<Vec3>& position, const Box& box, const ChunkCheck* first);
  bool needs_rebuild(const std::vector<Vec3>& position) const;
  // needs_rebuild's test one particle at a time, for a caller's pass over the particles:
  // the list holds `count` particles' build positions, and particle i at x keeps it valid.
  bool built_for(std::size_t count) const { return position_at_build_.size() == count; }
  bool keeps_valid(std::size_t i, const Vec3& x) const {
    return norm2(x - position_at_build_[i]) <= valid_distance2();
  }
  // The squared distance from its build position within which a particle keeps the list valid.
  double valid_distance2() const { return 0.25 * skin_ * skin_; }
  // The positions of the last build: a restart rebuilds from them, so that the pair order,
  // and with it every rounding, repeats.
  const std::vector<Vec3>& positions_at_build() const { return position_at_build_; }

  // Neighbours of i are neighbors()[offsets()[i] .. offsets()[i+1]). Made from the list by
  // slot when first asked for after a build (on any thread).
  const std::vector<std::int32_t>& neighbors() const {
    by_particle();
    return neighbors_;
  }
  const std::vector<std::size_t>& offsets() const {
    by_particle();
    return offsets_;
  }
  std::size_t pair_count() const { return pairs_; }

  // Each particle's partners (as particles) and their image codes as ranges: particle i's
  // (i < particles) are entries [begin[i], end[i]) of `neighbors` and `image_codes` (null when
  // the pairs have none), in neighbors()' order.
  struct PartnerRanges {
    std::size_t particles = 0;
    const std::int32_t* neighbors = nullptr;
    const std::uint8_t* image_codes = nullptr;
    const std::size_t* begin = nullptr;
    const std::size_t* end = nullptr;
  };
  // The list as the last build left it, without cell order: read in place, the list by
  // particle is not made (a copy of the whole list at every build, 4 % of an LJ liquid's
  // run); NeighborList makes it when first asked for. All null with cell order on, or
  // before a build.
  PartnerRanges built_order() const;
  // built_order() where there is one, else the list by particle (end = offsets() + 1).
  PartnerRanges partner_ranges() const;
  std::int64_t builds() const { return builds_; }
  void continue_build_count(std::int64_t builds) { builds_ = builds; }

  // When the box is at least three reaches wide along every periodic axis, each listed pair
  // also has a fixed periodic shift, valid until the next rebuild: x_i - x_j - shift is its
  // minimum-image separation, with no rounding in the force loop. Otherwise (small boxes)
  // image_codes() is empty and callers take minimum images.
  const std::vector<std::uint8_t>& image_codes() const {
    by_particle();
    return image_codes_;
  }
  // Whether the pairs have image codes (image_codes() not empty, here and by slot).
  bool coded() const { return coded_ && pairs_ > 0; }
  const std::array<Vec3, 27>& image_shifts() const { return image_shifts_; }

  // Cache order: with it on, each build also keeps the list in the particles' cell order
  // (cells along x, then y, then z; ascending index within a cell). A pair loop that
  // gathers positions into that order finds a particle's partners near it in memory,
  // whatever order the particles' indices are in (a liquid scrambles a lattice's within a
  // few thousand steps). The pairs are the same, listed under the same particle.
  void set_cell_order(bool on);
  struct CellOrdered {
    std::vector<std::int32_t> particle;     // by slot: the particle in that slot
    std::vector<std::size_t> offsets;       // by slot, as offsets()
    std::vector<std::int32_t> neighbors;    // slots
    std::vector<std::uint8_t> image_codes;  // as image_codes(), pair by pair
    // The list by slot as ranges (partners as slots): slot s's are [offsets[s], offsets[s + 1]).
    PartnerRanges ranges() const {
      if (offsets.empty()) return {};
      return {particle.size(), neighbors.data(), image_codes.data(), offsets.data(),
              offsets.data() + 1};
    }
  };
  // Empty (no particles) unless set_cell_order(true) preceded the last build.
  const CellOrdered& cell_ordered() const { return cell_ordered_; }
  // A pair loop's `chunks` chunks of the list's items: chunk c is items [starts[c],
  // starts[c + 1]). With cell order on, consecutive slots holding equal numbers of listed
  // pairs (as near as whole slots allow); else fixed_chunk_range's equal counts of particles,
  // whatever the threads' speeds (a force loop's per-chunk sums). Made when first asked for
  // after a build; one caller at a time.
  const std::vector<std::size_t>& pair_chunk_starts(int chunks) const;
  // For a pair loop over the list in `chunks` chunks (pair_chunk_starts) of its items
  // (particles, or slots with cell order on): the blocks each chunk's items and their
  // partners lie in.
  // Made when first asked for after a build, the list scanned in the order the build left
  // it (by particle, its ranges lie in no order: read so, a scan missed the cache on most
  // particles, 2.6 % of LJ 32000's samples); one caller at a time.
  const TouchedBlocks& touched_blocks(int chunks) const;

 private:
  struct Grid {
    std::array<int, 3> count{};
    Vec3 origin, inverse_width;
    std::array<int, 3> span{1, 1, 1};  // stencil half-width in cells, per axis
    bool shifted = true;               // each neighbouring cell reached through one periodic shift
    bool operator==(const Grid& o) const {
      return count == o.count && span == o.span && shifted == o.shifted;
    }
  };

 public:
  // The cells' stencils of the last build, a function of its grid and the box's periods alone.
  // A list made anew for the same particles in the same box (at the particles' sort, which
  // makes the integrator anew) takes them from its predecessor: making them took 0.5 ms a sort
  // on the 4000-sphere fluid's 18 400 cells. A build whose grid or periods differ from them
  // makes its own.
  struct Stencils {
    Grid grid;
    std::array<bool, 3> periodic{};
    std::vector<std::size_t> offsets;
    std::vector<std::int32_t> cells, ends;
    std::vector<std::uint8_t> codes;
  };
  // This list's stencils, moved out (it makes them again at its next build).
  Stencils take_stencils();
  void adopt_stencils(Stencils stencils);

 private:
  Grid make_grid(const std::vector<Vec3>& inside, const Box& box) const;
  void by_particle() const {
    if (by_particle_.stale.load(std::memory_order_acquire)) make_by_particle();
  }
  void make_by_particle() const;
  void rearrange_by_particle(const std::size_t* slot_of, const std::size_t* slot_offsets,
                             const std::int32_t* slot_neighbors, const std::int32_t* slot_particle,
                             const std::uint8_t* slot_codes, std::size_t n) const;
  void make_stencils(const Grid& grid, const Box& box);
  // `first` (the build's first pass, given where the grid is known before it): run on each
  // counting chunk before its count; a chunk it refuses counts nothing (false returned).
  using CountingChunkPass = std::function<bool(int chunk, std::size_t begin, std::size_t end)>;
  bool count_into_cells(std::size_t particle_count, std::size_t cell_count, int sort_chunks,
                        const CountingChunkPass* first = nullptr);

  double cutoff_, skin_;
  std::vector<std::array<std::int32_t, 2>> excluded_;  // sorted, i < j
  std::vector<std::size_t> excluded_offsets_;          // by first index
  std::vector<std::size_t> partner_offsets_;           // by particle, built with the above
  std::vector<std::int32_t> partners_;                 // each particle's excluded partners

  // Per cell, the neighbouring cells to scan, as runs of consecutive cells [cell, end)
  // with one periodic shift code each; kept while the grid is unchanged (always, for a
  // fixed periodic box).
  Grid stencil_grid_;
  std::array<bool, 3> stencil_periodic_{};
  std::vector<std::size_t> stencil_offsets_;
  std::vector<std::int32_t> stencil_cells_, stencil_ends_;
  std::vector<std::uint8_t> stencil_codes_;

  // Each chunk's part of the list during a build (kept: their capacity is reused).
  std::vector<std::vector<std::int32_t>> chunk_neighbors_;
  std::vector<std::vector<std::uint8_t>> chunk_codes_;
  // Each chunk's candidate slots and codes during its scan (kept, as the lists above).
  std::vector<std::vector<std::int32_t>> chunk_hit_slots_;
  std::vector<std::vector<std::uint8_t>> chunk_hit_codes_;
  // A build's arrays by particle and by slot (cell order), kept between builds: allocated
  // afresh, their pages were faulted in again on every build, on the calling thread alone
  // (LJ 32000, 2 threads: 3 % of the run's samples in page faults under the build).
  std::vector<Vec3> inside_, member_position_;
  std::vector<double> member_x_, member_y_, member_z_;    // member_position_ by component
  std::vector<float> member_xf_, member_yf_, member_zf_;  // the same in single precision
  std::vector<std::array<int, 3>> moved_, member_moved_;
  std::vector<std::int32_t> cell_of_, member_, member_cell_;
  // Per slot: the periods moved as a code 0..26 where each is -1..1, else 27 + slot (unique):
  // equal keys mean equal moves.
  std::vector<std::int32_t> member_moved_key_;
  std::vector<std::size_t> cell_start_, slot_of_;
  // Per chunk of particles of the counting sort: its particles per cell, then its next slots.
  std::vector<std::vector<std::size_t>> chunk_cell_fill_;
  // The joined list by slot (cell order), partners as particles: without cell order, kept
  // until the next build (built_order() reads it, the list by particle is made from it).
  std::vector<std::size_t> slot_offsets_;
  std::vector<std::int32_t> slot_neighbors_;
  std::vector<std::uint8_t> slot_codes_;
  // Without cell order, each particle's entries in the list by slot: [begin, end).
  std::vector<std::size_t> built_begin_, built_end_;

  // The list by particle, made from the list by slot when first asked for: `stale` until
  // then. Copies take the flag, not the lock.
  struct Pending {
    std::atomic<bool> stale{false};
    std::mutex mutex;
    Pending() = default;
    Pending(const Pending& other) : stale(other.stale.load()) {}
    Pending& operator=(const Pending& other) {
      stale.store(other.stale.load());
      return *this;
    }
  };
  mutable Pending by_particle_;
  mutable std::vector<std::int32_t> neighbors_;
  mutable std::vector<std::size_t> offsets_;
  mutable std::vector<std::uint8_t> image_codes_;
  std::size_t pairs_ = 0;
  bool coded_ = false;
  std::array<Vec3, 27> image_shifts_{};
  std::vector<Vec3> position_at_build_;
  std::int64_t builds_ = 0;
  bool cell_order_ = false;
  CellOrdered cell_ordered_;
  mutable TouchedBlocks touched_;
  mutable std::int64_t touched_build_ = -1;
  mutable std::vector<std::vector<char>> scan_marks_;  // touched_blocks()'s, per chunk of slots
  mutable std::vector<std::size_t> chunk_starts_;      // pair_chunk_starts()'
  mutable std::int64_t chunk_starts_build_ = -1;
};

// Of the 27 image shifts by code (image_shifts()), the code of the zero shift (the list's
// numbering, not assumed), or 255, never a code, if there is none: loops over the list skip
// the shift's subtraction where an entry has it.
inline int zero_shift_code(const Vec3* shifts) {
  int zero_shift = 255;
  for (int code = 26; code >= 0; --code) {
    const Vec3& s = shifts[code];
    if (s.x == 0.0 && s.y == 0.0 && s.z == 0.0) zero_shift = code;
  }
  return zero_shift;
}

}  // namespace deli
