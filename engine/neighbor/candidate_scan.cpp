#include "neighbor/candidate_scan.hpp"

#include <algorithm>
#include <cstddef>
#include <cstring>

#if defined(__AVX512F__) && defined(__AVX512VL__)
#include <immintrin.h>
#define DELI_SCAN_AVX512 1
#endif

namespace deli {

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

std::uint64_t repeated(std::uint8_t code) {
  std::uint64_t codes;
  std::memset(&codes, code, sizeof codes);
  return codes;
}
}  // namespace

// Eight candidates a vector (scan_block), the last one partial.
std::size_t scan_candidates(const double* x, const double* y, const double* z, std::size_t first,
                            std::size_t last, double ox, double oy, double oz, double within2,
                            std::uint8_t code, std::int32_t* slot_out, std::uint8_t* code_out,
                            std::size_t hits) {
  const __m512d px = _mm512_set1_pd(ox), py = _mm512_set1_pd(oy), pz = _mm512_set1_pd(oz);
  const __m512d reach = _mm512_set1_pd(within2);
  const std::uint64_t codes = repeated(code);
  for (std::size_t m = first; m < last; m += 8) {
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
  const std::uint64_t codes = repeated(code);
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

std::size_t scan_stencil(const double* x, const double* y, const double* z, const StencilRuns& runs,
                         std::size_t home_first, std::size_t home_last, std::uint8_t home_code,
                         std::size_t run_begin, std::size_t run_end, double xi, double yi,
                         double zi, double within2, std::int32_t* slot_out,
                         std::uint8_t* code_out) {
#ifdef DELI_SCAN_AVX512
  const __m512d reach = _mm512_set1_pd(within2);
  auto scan = [&](std::size_t first, std::size_t last, double ox, double oy, double oz,
                  std::uint8_t code, std::size_t hits) {
    return scan_run(x, y, z, first, last, ox, oy, oz, reach, code, slot_out, code_out, hits);
  };
#else
  auto scan = [&](std::size_t first, std::size_t last, double ox, double oy, double oz,
                  std::uint8_t code, std::size_t hits) {
    return scan_candidates(x, y, z, first, last, ox, oy, oz, within2, code, slot_out, code_out,
                           hits);
  };
#endif
  return walk_stencil(runs, home_first, home_last, home_code, run_begin, run_end, xi, yi, zi, scan);
}

}  // namespace deli
