#pragma once

#include <cstddef>
#include <cstdint>

namespace deli {

// The neighbour-list build's innermost loop: the candidates m in [first, last) of a run of
// cells (positions by slot as structures of arrays x, y, z), tested against one particle's
// position shifted by a periodic image (ox, oy, oz). Every candidate with
// (x_m - ox)^2 + (y_m - oy)^2 + (z_m - oz)^2 < within2 (summed in that order, NaN never
// within) is appended, in slot order, as its slot to slot_out and `code` to code_out from
// position `hits` on; returns the new hit count. The output arrays must have room for
// hits + (last - first) + kScanSlack entries: the vector form stores whole vectors past the
// last hit. Built for the build machine's CPU under DELI_NATIVE (AVX-512 or AVX2: the test
// by vector of eight or four and the hits compressed in registers); the same hits in the
// same order either way.
inline constexpr std::size_t kScanSlack = 16;
std::size_t scan_candidates(const double* x, const double* y, const double* z, std::size_t first,
                            std::size_t last, double ox, double oy, double oz, double within2,
                            std::uint8_t code, std::int32_t* slot_out, std::uint8_t* code_out,
                            std::size_t hits);

// One particle's whole scan: its home run [home_first, home_last) with image `home_code`, then
// the runs s in [run_begin, run_end) of its cell's stencil, run s covering the slots
// cell_start[cells[s]] to cell_start[ends[s]] with image codes[s]; each run as
// scan_candidates with the origin (xi, yi, zi) minus shifts[code] (x, y, z of 27 shifts).
// Appends from position 0 and returns the hit count: the hits of those scan_candidates calls,
// in their order. The outputs need room for all the runs' candidates and kScanSlack more. One call
// per particle rather than per run: a run holds a dozen candidates, and the runs' test latencies
// overlap only within a call.
struct StencilRuns {
  const std::size_t* cell_start;
  const std::int32_t* cells;
  const std::int32_t* ends;
  const std::uint8_t* codes;
  const double (*shifts)[3];
};
// Single-precision copies of the positions by slot, for a first test of each candidate in
// vectors of eight (AVX2 builds; the others test in doubles and ignore them): a candidate whose
// r^2 in floats is below within2_below is within reach, one at or above within2_above beyond
// it, and one in between is tested in doubles. The bounds must lie either side of within2 by
// more than the floats' rounding can move r^2 (float_bounds below); the hits are then the
// doubles' own.
struct FloatPositions {
  const float* x;
  const float* y;
  const float* z;
  float within2_below, within2_above;
};
// FloatPositions' bounds for candidates and origins whose coordinates are at most `largest` in
// magnitude and reach^2 = within2; false (test in doubles) where floats cannot hold them.
bool float_bounds(double largest, double within2, float& below, float& above);
// Whether scan_stencil reads FloatPositions in this build (AVX2 without AVX-512).
bool scan_reads_floats();
std::size_t scan_stencil(const double* x, const double* y, const double* z, const StencilRuns& runs,
                         std::size_t home_first, std::size_t home_last, std::uint8_t home_code,
                         std::size_t run_begin, std::size_t run_end, double xi, double yi,
                         double zi, double within2, std::int32_t* slot_out, std::uint8_t* code_out,
                         const FloatPositions* in_float = nullptr);

// A particle's hits made list entries (the build's step after scan_stencil, for image-coded
// lists): hit h in order is particle j = member[hit_slot[h]], dropped when j is one of the
// particle's `excluded_count` excluded partners, else appended to j_out (as j, or with
// `as_slots` as its slot hit_slot[h]) with hit_code[h] in code_out. A kept hit whose moved key
// (moved_key[hit_slot[h]]) differs from the particle's `key` needs its own image code: its
// place in j_out goes to recode_kept and h to recode_hit (the caller makes the code). A null
// moved_key says every key is the particle's: none to recode. Returns the number kept;
// *recode_count gets the number to recode. The outputs need room for hits + kScanSlack entries.
// Under DELI_NATIVE with AVX-512, sixteen hits a vector, with AVX2 eight (the partners compared
// by vector, at most kVectorExcluded of them; more are looked up one hit at a time): the same
// entries either way.
inline constexpr std::size_t kVectorExcluded = 4;
std::size_t keep_hits(const std::int32_t* member, const std::int32_t* moved_key, std::int32_t key,
                      const std::int32_t* hit_slot, const std::uint8_t* hit_code, std::size_t hits,
                      const std::int32_t* excluded, std::size_t excluded_count, std::int32_t* j_out,
                      std::uint8_t* code_out, std::uint32_t* recode_kept, std::uint32_t* recode_hit,
                      std::size_t* recode_count, bool as_slots = false);

}  // namespace deli
