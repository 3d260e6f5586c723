#include "neighbor/candidate_scan.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

#if defined(__AVX512F__) && defined(__AVX512VL__)
#include <immintrin.h>
#define DELI_SCAN_AVX512 1
// GCC 12 warns that the intrinsics' own _mm512_undefined_*() is (or may be) used
// uninitialized inside the conversions (a false positive: GCC PR 105593).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#elif defined(__AVX2__)
#include <immintrin.h>
#define DELI_SCAN_AVX2 1
#endif

namespace deli {

namespace {
// A run's code in every byte of a word, stored with the hits a vector at a time.
template <class Word>
[[maybe_unused]] Word repeated(std::uint8_t code) {
  Word codes;
  std::memset(&codes, code, sizeof codes);
  return codes;
}
}  // namespace

#ifdef DELI_SCAN_AVX512
namespace {
// The eight candidates from m on, lanes past `last` masked (they read nothing and never
// hit), tested against the origin (px, py, pz); appends the hits at `hits` and returns the
// new count. The hits' slots are compressed in a register and stored whole (a compressing
// store to memory is microcoded and slow on AMD's Zen 4); the run's code is stored as eight
// bytes (`codes`). Separate multiplies and adds in the scalar order: the same sums bit for
// bit (no contraction).
[[gnu::always_inline]] inline std::size_t scan_block(const double* x, const double* y,
                                                     const double* z, std::size_t m,
                                                     std::size_t last, __m512d px, __m512d py,
                                                     __m512d pz, __m512d reach, std::uint64_t codes,
                                                     std::int32_t* slot_out, std::uint8_t* code_out,
                                                     std::size_t hits) {
  const auto left = static_cast<std::ptrdiff_t>(last) - static_cast<std::ptrdiff_t>(m);
  const auto count = static_cast<unsigned>(std::clamp<std::ptrdiff_t>(left, 0, 8));
  const auto lanes = static_cast<__mmask8>((1u << count) - 1u);
  const __m512d dx = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes, x + m), px);
  const __m512d dy = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes, y + m), py);
  const __m512d dz = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes, z + m), pz);
  const __m512d r2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                   _mm512_mul_pd(dz, dz));
  const __mmask8 within = _mm512_mask_cmp_pd_mask(lanes, r2, reach, _CMP_LT_OQ);
  const __m256i slots = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(m)),
                                         _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(slot_out + hits),
                      _mm256_maskz_compress_epi32(within, slots));
  std::memcpy(code_out + hits, &codes, sizeof codes);
  return hits + static_cast<std::size_t>(__builtin_popcount(within));
}

}  // namespace

// Eight candidates a vector (scan_block), the last one partial.
std::size_t scan_candidates(const double* x, const double* y, const double* z, std::size_t first,
                            std::size_t last, double ox, double oy, double oz, double within2,
                            std::uint8_t code, std::int32_t* slot_out, std::uint8_t* code_out,
                            std::size_t hits) {
  const __m512d px = _mm512_set1_pd(ox), py = _mm512_set1_pd(oy), pz = _mm512_set1_pd(oz);
  const __m512d reach = _mm512_set1_pd(within2);
  const auto codes = repeated<std::uint64_t>(code);
  for (std::size_t m = first; m < last; m += 8) {
    hits = scan_block(x, y, z, m, last, px, py, pz, reach, codes, slot_out, code_out, hits);
  }
  return hits;
}
#elif defined(DELI_SCAN_AVX2)
namespace {
// For each mask of four lanes, the bytes that move its set lanes' 32-bit slots to the front
// in order (the rest zero).
struct CompressTable {
  alignas(16) std::uint8_t bytes[16][16] = {};
  constexpr CompressTable() {
    for (int mask = 0; mask < 16; ++mask) {
      int place = 0;
      for (int lane = 0; lane < 4; ++lane) {
        if (!(mask >> lane & 1)) continue;
        for (int b = 0; b < 4; ++b)
          bytes[mask][4 * place + b] = static_cast<std::uint8_t>(4 * lane + b);
        ++place;
      }
      for (int b = 4 * place; b < 16; ++b) bytes[mask][b] = 0x80;
    }
  }
};
constexpr CompressTable kCompress;

// scan_block's four-lane form: the candidates m..m+3, lanes past `last` masked (a masked
// load reads nothing; they never hit), the hits' slots compressed in a register by a byte
// shuffle and stored whole, the run's code stored as four bytes. The same tests as the scalar
// scan (separate multiplies and adds in its order).
[[gnu::always_inline]] inline std::size_t scan_block(const double* x, const double* y,
                                                     const double* z, std::size_t m,
                                                     std::size_t last, __m256d px, __m256d py,
                                                     __m256d pz, __m256d reach, std::uint32_t codes,
                                                     std::int32_t* slot_out, std::uint8_t* code_out,
                                                     std::size_t hits) {
  const auto left = static_cast<long long>(last) - static_cast<long long>(m);
  const __m256i lanes =
      _mm256_cmpgt_epi64(_mm256_set1_epi64x(left), _mm256_setr_epi64x(0, 1, 2, 3));
  const __m256d dx = _mm256_sub_pd(_mm256_maskload_pd(x + m, lanes), px);
  const __m256d dy = _mm256_sub_pd(_mm256_maskload_pd(y + m, lanes), py);
  const __m256d dz = _mm256_sub_pd(_mm256_maskload_pd(z + m, lanes), pz);
  const __m256d r2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                                   _mm256_mul_pd(dz, dz));
  const auto within = static_cast<unsigned>(_mm256_movemask_pd(
      _mm256_and_pd(_mm256_castsi256_pd(lanes), _mm256_cmp_pd(r2, reach, _CMP_LT_OQ))));
  const __m128i slots =
      _mm_add_epi32(_mm_set1_epi32(static_cast<int>(m)), _mm_setr_epi32(0, 1, 2, 3));
  _mm_storeu_si128(
      reinterpret_cast<__m128i*>(slot_out + hits),
      _mm_shuffle_epi8(slots,
                       _mm_load_si128(reinterpret_cast<const __m128i*>(kCompress.bytes[within]))));
  std::memcpy(code_out + hits, &codes, sizeof codes);
  return hits + static_cast<std::size_t>(__builtin_popcount(within));
}

// For each mask of eight lanes, its set lanes' numbers in order, then 0x80 (a byte shuffle's
// zero): widened, a permutation of 32-bit lanes that moves the set lanes to the front; as
// bytes, the same for eight bytes.
struct CompressTable8 {
  alignas(8) std::uint8_t lanes[256][8] = {};
  constexpr CompressTable8() {
    for (int mask = 0; mask < 256; ++mask) {
      int place = 0;
      for (int lane = 0; lane < 8; ++lane) {
        if (mask >> lane & 1) lanes[mask][place++] = static_cast<std::uint8_t>(lane);
      }
      for (; place < 8; ++place) lanes[mask][place] = 0x80;
    }
  }
};
constexpr CompressTable8 kCompress8;

// scan_block's first test in single precision, eight candidates a vector (floats: `xf`, `yf`,
// `zf`, origin px, py, pz). Below `below` a candidate is within reach, at or above `above`
// beyond it (FloatPositions), and in between, rarely, it is tested as scan_block tests it, in
// doubles (x, y, z against ox, oy, oz), lane by lane. The same hits in the same order.
[[gnu::always_inline]] inline std::size_t scan_block_float(
    const FloatPositions& f, const double* x, const double* y, const double* z, std::size_t m,
    std::size_t last, __m256 px, __m256 py, __m256 pz, __m256 below, __m256 above, double ox,
    double oy, double oz, double within2, std::uint64_t codes, std::int32_t* slot_out,
    std::uint8_t* code_out, std::size_t hits) {
  const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const auto left = static_cast<int>(
      std::clamp<long long>(static_cast<long long>(last) - static_cast<long long>(m), 0, 8));
  const __m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(left), iota);
  const __m256 dx = _mm256_sub_ps(_mm256_maskload_ps(f.x + m, lanes), px);
  const __m256 dy = _mm256_sub_ps(_mm256_maskload_ps(f.y + m, lanes), py);
  const __m256 dz = _mm256_sub_ps(_mm256_maskload_ps(f.z + m, lanes), pz);
  const __m256 r2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                  _mm256_mul_ps(dz, dz));
  const __m256 listed = _mm256_castsi256_ps(lanes);
  auto within = static_cast<unsigned>(
      _mm256_movemask_ps(_mm256_and_ps(listed, _mm256_cmp_ps(r2, below, _CMP_LT_OQ))));
  const unsigned unsure = static_cast<unsigned>(_mm256_movemask_ps(
                              _mm256_and_ps(listed, _mm256_cmp_ps(r2, above, _CMP_LT_OQ)))) &
                          ~within;
  if (unsure != 0) [[unlikely]] {
    for (unsigned u = unsure; u != 0; u &= u - 1) {
      const std::size_t k = m + static_cast<std::size_t>(__builtin_ctz(u));
      const double ex = x[k] - ox, ey = y[k] - oy, ez = z[k] - oz;
      within |= static_cast<unsigned>(ex * ex + ey * ey + ez * ez < within2) << __builtin_ctz(u);
    }
  }
  std::uint64_t order;
  std::memcpy(&order, kCompress8.lanes[within], sizeof order);
  const __m256i slots = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(m)), iota);
  _mm256_storeu_si256(
      reinterpret_cast<__m256i*>(slot_out + hits),
      _mm256_permutevar8x32_epi32(
          slots, _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(order)))));
  std::memcpy(code_out + hits, &codes, sizeof codes);
  return hits + static_cast<std::size_t>(__builtin_popcount(within));
}

}  // namespace

// Four candidates a vector (scan_block), the last one partial; a particle's runs each so
// (scan_stencil). Unlike the AVX-512 form, no vectors whatever the run's length: on AMD's
// Zen 3 four such (sixteen candidates) cost more than the trip counts the predictor loses
// (list phase, one thread, with none against four: LJ 32000 0.86x, the rigid melt 0.92x, the
// hard-sphere fluid at 32000 0.74x, the default input 0.76x).
std::size_t scan_candidates(const double* x, const double* y, const double* z, std::size_t first,
                            std::size_t last, double ox, double oy, double oz, double within2,
                            std::uint8_t code, std::int32_t* slot_out, std::uint8_t* code_out,
                            std::size_t hits) {
  const __m256d px = _mm256_set1_pd(ox), py = _mm256_set1_pd(oy), pz = _mm256_set1_pd(oz);
  const __m256d reach = _mm256_set1_pd(within2);
  const auto codes = repeated<std::uint32_t>(code);
  for (std::size_t m = first; m < last; m += 4) {
    hits = scan_block(x, y, z, m, last, px, py, pz, reach, codes, slot_out, code_out, hits);
  }
  return hits;
}
#else
// Every candidate stored, the count advanced for hits only (no branch on the distance
// test, which the predictor would lose about a third of the time).
std::size_t scan_candidates(const double* x, const double* y, const double* z, std::size_t first,
                            std::size_t last, double ox, double oy, double oz, double within2,
                            std::uint8_t code, std::int32_t* slot_out, std::uint8_t* code_out,
                            std::size_t hits) {
  for (std::size_t m = first; m < last; ++m) {
    const double dx = x[m] - ox, dy = y[m] - oy, dz = z[m] - oz;
    slot_out[hits] = static_cast<std::int32_t>(m);
    code_out[hits] = code;
    hits += dx * dx + dy * dy + dz * dz < within2;
  }
  return hits;
}
#endif

#ifdef DELI_SCAN_AVX512
namespace {
// The candidates [first, last) tested against (ox, oy, oz) eight at a time: two vectors
// whatever the run's length (most runs hold fewer than 16 candidates; an empty mask reads
// and adds nothing), so the loop's trip count, which the predictor would often lose, is
// tested only past 16. The same tests, hits and order as scan_candidates.
[[gnu::always_inline]] inline std::size_t scan_run(const double* x, const double* y,
                                                   const double* z, std::size_t first,
                                                   std::size_t last, double ox, double oy,
                                                   double oz, __m512d reach, std::uint8_t code,
                                                   std::int32_t* slot_out, std::uint8_t* code_out,
                                                   std::size_t hits) {
  const __m512d px = _mm512_set1_pd(ox), py = _mm512_set1_pd(oy), pz = _mm512_set1_pd(oz);
  const auto codes = repeated<std::uint64_t>(code);
  auto block = [&](std::size_t m) {
    hits = scan_block(x, y, z, m, last, px, py, pz, reach, codes, slot_out, code_out, hits);
  };
  block(first);
  block(first + 8);
  for (std::size_t m = first + 16; m < last; m += 8) block(m);
  return hits;
}
}  // namespace
#endif

namespace {
// The particle's home run, then its stencil's runs s in [run_begin, run_end), each handed to
// scan(first, last, ox, oy, oz, code, hits) with the origin less the run's image shift.
template <class Scan>
std::size_t walk_stencil(const StencilRuns& runs, std::size_t home_first, std::size_t home_last,
                         std::uint8_t home_code, std::size_t run_begin, std::size_t run_end,
                         double xi, double yi, double zi, Scan&& scan) {
  const double* shift = runs.shifts[home_code];
  std::size_t hits = scan(home_first, home_last, xi - shift[0], yi - shift[1], zi - shift[2],
                          home_code, std::size_t{0});
  for (std::size_t s = run_begin; s < run_end; ++s) {
    const std::uint8_t code = runs.codes[s];
    shift = runs.shifts[code];
    hits = scan(runs.cell_start[runs.cells[s]], runs.cell_start[runs.ends[s]], xi - shift[0],
                yi - shift[1], zi - shift[2], code, hits);
  }
  return hits;
}
}  // namespace

bool scan_reads_floats() {
#if defined(DELI_SCAN_AVX2)
  return true;
#else
  return false;
#endif
}

// Each coordinate and origin rounded to a float moves by at most `largest` 2^-24, and a
// difference d of two floats rounds by |d| 2^-24: a component's error e is at most
// 2 largest 2^-24 + r 2^-24 for candidates within r, and its square's |d_f^2 - d^2| at most
// e (2 |d| + e). Summed over the axes (|dx| + |dy| + |dz| <= sqrt(3) r), with the floats'
// three products and two sums (4 r^2 2^-24), for r up to twice the reach; four times that
// either side of within2. Beyond twice the reach r^2 in floats is far above the bound.
bool float_bounds(double largest, double within2, float& below, float& above) {
  if (!(largest >= 0.0 && largest < 1e30 && within2 > 0.0 && within2 < 1e30)) return false;
  const double u = 0x1p-24, r = 2.0 * std::sqrt(within2);
  const double e = 2.0 * largest * u + r * u;
  const double error = e * (2.0 * std::sqrt(3.0) * r + 3.0 * e) + 4.0 * u * r * r;
  const double low = within2 - 4.0 * error, high = within2 + 4.0 * error;
  if (!(low > 0.0)) return false;
  below = std::nextafter(static_cast<float>(low), 0.0f);
  above = std::nextafter(static_cast<float>(high), std::numeric_limits<float>::infinity());
  return true;
}

std::size_t scan_stencil(const double* x, const double* y, const double* z, const StencilRuns& runs,
                         std::size_t home_first, std::size_t home_last, std::uint8_t home_code,
                         std::size_t run_begin, std::size_t run_end, double xi, double yi,
                         double zi, double within2, std::int32_t* slot_out, std::uint8_t* code_out,
                         [[maybe_unused]] const FloatPositions* in_float) {
#ifdef DELI_SCAN_AVX512
  const __m512d reach = _mm512_set1_pd(within2);
  auto scan = [&](std::size_t first, std::size_t last, double ox, double oy, double oz,
                  std::uint8_t code, std::size_t hits) {
    return scan_run(x, y, z, first, last, ox, oy, oz, reach, code, slot_out, code_out, hits);
  };
#else
#ifdef DELI_SCAN_AVX2
  if (in_float) {
    const FloatPositions f = *in_float;
    const __m256 below = _mm256_set1_ps(f.within2_below), above = _mm256_set1_ps(f.within2_above);
    auto scan_float = [&](std::size_t first, std::size_t last, double ox, double oy, double oz,
                          std::uint8_t code, std::size_t hits) {
      const __m256 px = _mm256_set1_ps(static_cast<float>(ox));
      const __m256 py = _mm256_set1_ps(static_cast<float>(oy));
      const __m256 pz = _mm256_set1_ps(static_cast<float>(oz));
      const auto codes = repeated<std::uint64_t>(code);
      for (std::size_t m = first; m < last; m += 8) {
        hits = scan_block_float(f, x, y, z, m, last, px, py, pz, below, above, ox, oy, oz, within2,
                                codes, slot_out, code_out, hits);
      }
      return hits;
    };
    return walk_stencil(runs, home_first, home_last, home_code, run_begin, run_end, xi, yi, zi,
                        scan_float);
  }
#endif
  auto scan = [&](std::size_t first, std::size_t last, double ox, double oy, double oz,
                  std::uint8_t code, std::size_t hits) {
    return scan_candidates(x, y, z, first, last, ox, oy, oz, within2, code, slot_out, code_out,
                           hits);
  };
#endif
  return walk_stencil(runs, home_first, home_last, home_code, run_begin, run_end, xi, yi, zi, scan);
}

namespace {
std::size_t keep_hits_one_by_one(const std::int32_t* member, const std::int32_t* moved_key,
                                 std::int32_t key, const std::int32_t* hit_slot,
                                 const std::uint8_t* hit_code, std::size_t hits,
                                 const std::int32_t* excluded, std::size_t excluded_count,
                                 std::int32_t* j_out, std::uint8_t* code_out,
                                 std::uint32_t* recode_kept, std::uint32_t* recode_hit,
                                 std::size_t* recode_count, bool as_slots) {
  std::size_t kept = 0, recode = 0;
  const std::int32_t* const excluded_end = excluded + excluded_count;
  for (std::size_t h = 0; h < hits; ++h) {
    const auto m = static_cast<std::size_t>(hit_slot[h]);
    const std::int32_t j = member[m];
    if (std::find(excluded, excluded_end, j) != excluded_end) continue;
    if (moved_key && moved_key[m] != key) {
      recode_kept[recode] = static_cast<std::uint32_t>(kept);
      recode_hit[recode++] = static_cast<std::uint32_t>(h);
    }
    code_out[kept] = hit_code[h];
    j_out[kept++] = as_slots ? hit_slot[h] : j;
  }
  *recode_count = recode;
  return kept;
}
}  // namespace

#ifdef DELI_SCAN_AVX512
namespace {
// Sixteen hits a vector: the members and moved keys gathered, the excluded partners (at most
// kVectorExcluded) compared, the kept lanes compressed in registers and stored whole (the
// outputs have slack), the codes widened to 32 bits to be compressed alike and narrowed back.
std::size_t keep_hits_by_vector(const std::int32_t* member, const std::int32_t* moved_key,
                                std::int32_t key, const std::int32_t* hit_slot,
                                const std::uint8_t* hit_code, std::size_t hits,
                                const std::int32_t* excluded, std::size_t excluded_count,
                                std::int32_t* j_out, std::uint8_t* code_out,
                                std::uint32_t* recode_kept, std::uint32_t* recode_hit,
                                std::size_t* recode_count, bool as_slots) {
  __m512i partner[kVectorExcluded];
  for (std::size_t e = 0; e < kVectorExcluded; ++e) {
    // Unused places repeat a partner: the same test again.
    partner[e] = _mm512_set1_epi32(excluded_count ? excluded[e < excluded_count ? e : 0] : -1);
  }
  const __m512i key_v = _mm512_set1_epi32(key);
  const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  std::size_t kept = 0, recode = 0;
  for (std::size_t h = 0; h < hits; h += 16) {
    const std::size_t count = hits - h < 16 ? hits - h : 16;
    const auto lanes = static_cast<__mmask16>((1u << count) - 1u);
    const __m512i slot = _mm512_maskz_loadu_epi32(lanes, hit_slot + h);
    // The members are read only where they are kept or compared.
    const __m512i j =
        as_slots && !excluded_count
            ? slot
            : _mm512_mask_i32gather_epi32(_mm512_set1_epi32(-1), lanes, slot, member, 4);
    // Without moved keys (all the particle's), nothing to recode and nothing to gather.
    const __m512i moved =
        moved_key ? _mm512_mask_i32gather_epi32(key_v, lanes, slot, moved_key, 4) : key_v;
    __mmask16 keep = lanes;
    if (excluded_count) {
      for (std::size_t e = 0; e < kVectorExcluded; ++e) {
        keep &= _mm512_cmpneq_epi32_mask(j, partner[e]);
      }
    }
    // Sixteen codes read whole: hit_code has room for kScanSlack past the hits (the lanes
    // past them are not kept).
    const __m512i code =
        _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(hit_code + h)));
    _mm512_storeu_si512(j_out + kept, _mm512_maskz_compress_epi32(keep, as_slots ? slot : j));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(code_out + kept),
                     _mm512_cvtepi32_epi8(_mm512_maskz_compress_epi32(keep, code)));
    const auto kept_here = static_cast<unsigned>(__builtin_popcount(keep));
    if (keep & _mm512_cmpneq_epi32_mask(moved, key_v)) {
      // In the kept lanes' order: their places in j_out and hit numbers, for those to recode.
      const __m512i place = _mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(kept)), iota);
      const __m512i kept_hit = _mm512_maskz_compress_epi32(
          keep, _mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(h)), iota));
      const __mmask16 kept_differs =
          _mm512_mask_cmpneq_epi32_mask(static_cast<__mmask16>((1u << kept_here) - 1u),
                                        _mm512_maskz_compress_epi32(keep, moved), key_v);
      _mm512_mask_compressstoreu_epi32(recode_kept + recode, kept_differs, place);
      _mm512_mask_compressstoreu_epi32(recode_hit + recode, kept_differs, kept_hit);
      recode += static_cast<std::size_t>(__builtin_popcount(kept_differs));
    }
    kept += kept_here;
  }
  *recode_count = recode;
  return kept;
}
}  // namespace
#elif defined(DELI_SCAN_AVX2)
namespace {

// The AVX-512 keep_hits_by_vector's form in eight-lane AVX2 vectors: the members and moved
// keys gathered, the excluded partners compared, the kept lanes moved to the front by a
// permutation from a table and stored whole (the outputs have slack), the codes by a byte
// shuffle with the same table; the hits to recode, rare, listed lane by lane.
std::size_t keep_hits_by_vector(const std::int32_t* member, const std::int32_t* moved_key,
                                std::int32_t key, const std::int32_t* hit_slot,
                                const std::uint8_t* hit_code, std::size_t hits,
                                const std::int32_t* excluded, std::size_t excluded_count,
                                std::int32_t* j_out, std::uint8_t* code_out,
                                std::uint32_t* recode_kept, std::uint32_t* recode_hit,
                                std::size_t* recode_count, bool as_slots) {
  __m256i partner[kVectorExcluded];
  for (std::size_t e = 0; e < kVectorExcluded; ++e) {
    // Unused places repeat a partner: the same test again.
    partner[e] = _mm256_set1_epi32(excluded_count ? excluded[e < excluded_count ? e : 0] : -1);
  }
  const __m256i key_v = _mm256_set1_epi32(key);
  const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  std::size_t kept = 0, recode = 0;
  for (std::size_t h = 0; h < hits; h += 8) {
    const std::size_t count = hits - h < 8 ? hits - h : 8;
    const __m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(count)), iota);
    const __m256i slot = _mm256_maskload_epi32(hit_slot + h, lanes);
    // The members are read only where they are kept or compared.
    const __m256i j =
        as_slots && !excluded_count
            ? slot
            : _mm256_mask_i32gather_epi32(_mm256_set1_epi32(-1), member, slot, lanes, 4);
    // Without moved keys (all the particle's), nothing to recode and nothing to gather.
    const __m256i moved =
        moved_key ? _mm256_mask_i32gather_epi32(key_v, moved_key, slot, lanes, 4) : key_v;
    __m256i keep_v = lanes;
    if (excluded_count) {
      for (std::size_t e = 0; e < kVectorExcluded; ++e) {
        keep_v = _mm256_andnot_si256(_mm256_cmpeq_epi32(j, partner[e]), keep_v);
      }
    }
    const auto keep = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(keep_v)));
    std::uint64_t order;
    std::memcpy(&order, kCompress8.lanes[keep], sizeof order);
    const __m128i order_bytes = _mm_cvtsi64_si128(static_cast<long long>(order));
    _mm256_storeu_si256(
        reinterpret_cast<__m256i*>(j_out + kept),
        _mm256_permutevar8x32_epi32(as_slots ? slot : j, _mm256_cvtepu8_epi32(order_bytes)));
    // Eight codes read whole: hit_code has room for kScanSlack past the hits (the lanes past
    // them are not kept).
    std::uint64_t codes;
    std::memcpy(&codes, hit_code + h, sizeof codes);
    _mm_storel_epi64(
        reinterpret_cast<__m128i*>(code_out + kept),
        _mm_shuffle_epi8(_mm_cvtsi64_si128(static_cast<long long>(codes)), order_bytes));
    const auto differs = keep & ~static_cast<unsigned>(_mm256_movemask_ps(
                                    _mm256_castsi256_ps(_mm256_cmpeq_epi32(moved, key_v))));
    if (differs) {
      // In the kept lanes' order: their places in j_out and hit numbers, for those to recode.
      auto place = static_cast<std::uint32_t>(kept);
      for (unsigned m = keep; m != 0; m &= m - 1, ++place) {
        const int lane = __builtin_ctz(m);
        if (differs >> lane & 1u) {
          recode_kept[recode] = place;
          recode_hit[recode++] = static_cast<std::uint32_t>(h) + static_cast<std::uint32_t>(lane);
        }
      }
    }
    kept += static_cast<std::size_t>(__builtin_popcount(keep));
  }
  *recode_count = recode;
  return kept;
}
}  // namespace
#endif

std::size_t keep_hits(const std::int32_t* member, const std::int32_t* moved_key, std::int32_t key,
                      const std::int32_t* hit_slot, const std::uint8_t* hit_code, std::size_t hits,
                      const std::int32_t* excluded, std::size_t excluded_count, std::int32_t* j_out,
                      std::uint8_t* code_out, std::uint32_t* recode_kept, std::uint32_t* recode_hit,
                      std::size_t* recode_count, bool as_slots) {
#if defined(DELI_SCAN_AVX512) || defined(DELI_SCAN_AVX2)
  if (excluded_count <= kVectorExcluded) {
    return keep_hits_by_vector(member, moved_key, key, hit_slot, hit_code, hits, excluded,
                               excluded_count, j_out, code_out, recode_kept, recode_hit,
                               recode_count, as_slots);
  }
#endif
  return keep_hits_one_by_one(member, moved_key, key, hit_slot, hit_code, hits, excluded,
                              excluded_count, j_out, code_out, recode_kept, recode_hit,
                              recode_count, as_slots);
}

}  // namespace deli
