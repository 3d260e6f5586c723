#include <cstring>
#include <stdexcept>
#include <vector>

#include "neighbor/neighbor_list.hpp"
#include "pair/lennard_jones.hpp"

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
#include <immintrin.h>
#define DELI_LJ_AVX512 1
// GCC 12 warns that the intrinsics' own _mm512_undefined_pd() is (or may be) used
// uninitialized inside the extracts and reductions (a false positive: GCC PR 105593).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#elif defined(__AVX2__)
#include <immintrin.h>
#define DELI_LJ_AVX2 1
#endif

namespace deli {

#if defined(DELI_LJ_AVX512) || defined(DELI_LJ_AVX2)
namespace {

// Given as ranges (ends), particle i's partners need not follow i-1's (the list by particle
// read in the build's cell order): the entries of the particle four ahead fetched early, as
// the hardware's stream prefetch then does not (LJ 32000: this loop took 1.25x its time on
// the list by particle without, 1.03-1.07x with; the build saves the list's copy, 0.87x).
inline void prefetch_partners_ahead(const VectorPairChunk& c, std::int32_t i) {
  if (c.ends && i + 4 < c.last) {
    const std::size_t next = c.offsets[i + 4], last = c.ends[i + 4];
    const char* l = reinterpret_cast<const char*>(c.list + next);
    const char* l_end = reinterpret_cast<const char*>(c.list + last);
    for (; l < l_end + 63; l += 64) _mm_prefetch(l, _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(c.codes + next), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(c.codes + last), _MM_HINT_T0);
  }
}

// Energy and virial pair by pair in list order, as the scalar loop adds them: the same sums
// bit for bit (a lattice's equal terms round alike, and eight lane sums moved a 32000-atom
// energy by 3.5e-12 of itself from the other engines', whose sums are in this order too).
// pair[q][l]: lane l's energy less the shift (q = 0) and its virial terms xx, yy, zz, xy,
// xz, yz (q = 1..6); `in`: the lanes inside the cutoff. Tallies are rare steps: the cost
// does not show.
inline void add_tallies_in_lane_order(const double (&pair)[7][8], unsigned in, double& energy,
                                      SymTensor& w) {
  for (unsigned m = in; m != 0; m &= m - 1) {
    const int l = __builtin_ctz(m);
    energy += pair[0][l];
    w.xx += pair[1][l], w.yy += pair[2][l], w.zz += pair[3][l];
    w.xy += pair[4][l], w.xz += pair[5][l], w.yz += pair[6][l];
  }
}

}  // namespace
#endif

#ifdef DELI_LJ_AVX512
namespace {

// Eight partners' positions (padded, 32 bytes each) as x, y and z vectors: eight 256-bit
// loads and a transpose. Gathers (vgatherdpd) were twice as slow here on AMD's Zen 4.
inline void load_transposed(const PaddedVec3* x, const std::int32_t* j, __m512d& px, __m512d& py,
                            __m512d& pz) {
  auto pair = [&](int a, int b) {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_load_pd(&x[j[a]].x)),
                              _mm256_load_pd(&x[j[b]].x), 1);
  };
  const __m512d a = pair(0, 4), b = pair(1, 5), c = pair(2, 6), d = pair(3, 7);
  const __m512d ab_xz = _mm512_unpacklo_pd(a, b);  // x0 x1 z0 z1 | x4 x5 z4 z5
  const __m512d ab_y = _mm512_unpackhi_pd(a, b);   // y0 y1 -  -  | y4 y5 -  -
  const __m512d cd_xz = _mm512_unpacklo_pd(c, d);
  const __m512d cd_y = _mm512_unpackhi_pd(c, d);
  const __m512i first = _mm512_setr_epi64(0, 1, 8, 9, 4, 5, 12, 13);
  const __m512i second = _mm512_setr_epi64(2, 3, 10, 11, 6, 7, 14, 15);
  px = _mm512_permutex2var_pd(ab_xz, first, cd_xz);
  py = _mm512_permutex2var_pd(ab_y, first, cd_y);
  pz = _mm512_permutex2var_pd(ab_xz, second, cd_xz);
}

// f[j[l]] -= (fx, fy, fz)[l] for the eight lanes l: the transpose back, then one 256-bit
// load, subtract and store per lane (a lane without a pair subtracts +0: no change).
inline void subtract_transposed(PaddedVec3* f, const std::int32_t* j, __m512d fx, __m512d fy,
                                __m512d fz) {
  const __m512d zero = _mm512_setzero_pd();
  const __m512i first = _mm512_setr_epi64(0, 1, 8, 9, 4, 5, 12, 13);
  const __m512i second = _mm512_setr_epi64(2, 3, 10, 11, 6, 7, 14, 15);
  const __m512d xz01 = _mm512_permutex2var_pd(fx, first, fz);  // x0 x1 z0 z1 | x4 x5 z4 z5
  const __m512d xz23 = _mm512_permutex2var_pd(fx, second, fz);
  const __m512d y01 = _mm512_permutex2var_pd(fy, first, zero);  // y0 y1 0 0 | y4 y5 0 0
  const __m512d y23 = _mm512_permutex2var_pd(fy, second, zero);
  const __m512d l04 = _mm512_unpacklo_pd(xz01, y01);  // lane 0 | lane 4, as x y z 0
  const __m512d l15 = _mm512_unpackhi_pd(xz01, y01);
  const __m512d l26 = _mm512_unpacklo_pd(xz23, y23);
  const __m512d l37 = _mm512_unpackhi_pd(xz23, y23);
  auto subtract = [&](int lane, __m256d v) {
    double* q = &f[j[lane]].x;
    _mm256_store_pd(q, _mm256_sub_pd(_mm256_load_pd(q), v));
  };
  subtract(0, _mm512_castpd512_pd256(l04));
  subtract(1, _mm512_castpd512_pd256(l15));
  subtract(2, _mm512_castpd512_pd256(l26));
  subtract(3, _mm512_castpd512_pd256(l37));
  subtract(4, _mm512_extractf64x4_pd(l04, 1));
  subtract(5, _mm512_extractf64x4_pd(l15, 1));
  subtract(6, _mm512_extractf64x4_pd(l26, 1));
  subtract(7, _mm512_extractf64x4_pd(l37, 1));
}

// The 27 image shifts of one axis as a 32-entry table in four vectors, looked up by code
// with two permutes and a blend (no memory access).
struct ShiftTable {
  __m512d t[4];
  ShiftTable(const Vec3* shifts, int axis) {
    alignas(64) double v[32] = {};
    for (int c = 0; c < 27; ++c) v[c] = shifts[c][axis];
    for (int q = 0; q < 4; ++q) t[q] = _mm512_load_pd(v + 8 * q);
  }
  __m512d operator()(__m512i code) const {
    const __m512d low = _mm512_permutex2var_pd(t[0], code, t[1]);
    const __m512d high = _mm512_permutex2var_pd(t[2], code, t[3]);
    return _mm512_mask_blend_pd(_mm512_test_epi64_mask(code, _mm512_set1_epi64(16)), low, high);
  }
};

// The eight lanes' sum in lane_order_loop's order: ((0 + 4) + (2 + 6)) + ((1 + 5) + (3 + 7)).
inline double lane_sum(__m512d v) {
  const __m256d half = _mm256_add_pd(_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd(v, 1));
  const __m128d quarter = _mm_add_pd(_mm256_castpd256_pd128(half), _mm256_extractf128_pd(half, 1));
  return _mm_cvtsd_f64(_mm_add_sd(quarter, _mm_unpackhi_pd(quarter, quarter)));
}

template <bool kTally>
double loop(const LennardJones::Params& p, const VectorPairChunk& c, SymTensor& virial) {
  const __m512d cutoff2 = _mm512_set1_pd(p.cutoff2), one = _mm512_set1_pd(1.0);
  const __m512d lj1 = _mm512_set1_pd(p.lj1), lj2 = _mm512_set1_pd(p.lj2);
  const __m512d lj3 = _mm512_set1_pd(p.lj3), lj4 = _mm512_set1_pd(p.lj4);
  const __m512d shift = _mm512_set1_pd(p.energy_shift);
  const ShiftTable sx(c.shifts, 0), sy(c.shifts, 1), sz(c.shifts, 2);
  const __m128i unshifted = _mm_set1_epi8(static_cast<char>(zero_shift_code(c.shifts)));
  double energy = 0.0;
  SymTensor w;
  alignas(32) std::int32_t tail[8];
  for (std::int32_t i = c.first; i < c.last; ++i) {
    const __m512d xi = _mm512_set1_pd(c.x[i].x), yi = _mm512_set1_pd(c.x[i].y),
                  zi = _mm512_set1_pd(c.x[i].z);
    __m512d fxi = _mm512_setzero_pd(), fyi = fxi, fzi = fxi;
    const std::size_t end = c.ends ? c.ends[i] : c.offsets[i + 1];
    prefetch_partners_ahead(c, i);
    for (std::size_t k = c.offsets[i]; k < end; k += 8) {
      // The partners' slots read one by one from the list (cheaper than from a vector);
      // in the last, partial vector lanes past the list's end take particle i itself: its
      // position is readable and the +0 subtracted from its force changes nothing.
      const std::size_t left = end - k;
      const auto lanes = static_cast<__mmask8>(left >= 8 ? 0xffu : (1u << left) - 1);
      const std::int32_t* j = c.list + k;
      if (left < 8) {
        _mm256_store_si256(reinterpret_cast<__m256i*>(tail),
                           _mm256_mask_loadu_epi32(_mm256_set1_epi32(i), lanes, j));
        j = tail;
      }
      __m512d xj, yj, zj;
      load_transposed(c.x, j, xj, yj, zj);
      __m512d dx = _mm512_sub_pd(xi, xj), dy = _mm512_sub_pd(yi, yj), dz = _mm512_sub_pd(zi, zj);
      // Most vectors cross no periodic boundary: every lane's code the unshifted image's.
      const __m128i codes = _mm_mask_loadu_epi8(unshifted, lanes, c.codes + k);
      if (_mm_cmpneq_epi8_mask(codes, unshifted) != 0) {
        const __m512i code = _mm512_cvtepu8_epi64(codes);
        dx = _mm512_sub_pd(dx, sx(code));
        dy = _mm512_sub_pd(dy, sy(code));
        dz = _mm512_sub_pd(dz, sz(code));
      }
      const __m512d r2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                       _mm512_mul_pd(dz, dz));
      const __mmask8 in = _mm512_mask_cmp_pd_mask(lanes, r2, cutoff2, _CMP_LT_OQ);
      // The scalar evaluator's operations in its order: each pair's f/r and energy are the
      // scalar loop's bit for bit; lanes outside the cutoff are +0.
      const __m512d r2inv = _mm512_maskz_div_pd(in, one, r2);
      const __m512d r6inv = _mm512_mul_pd(_mm512_mul_pd(r2inv, r2inv), r2inv);
      const __m512d f_over_r =
          _mm512_mul_pd(_mm512_mul_pd(r6inv, _mm512_sub_pd(_mm512_mul_pd(lj1, r6inv), lj2)), r2inv);
      const __m512d fx = _mm512_maskz_mul_pd(in, dx, f_over_r);
      const __m512d fy = _mm512_maskz_mul_pd(in, dy, f_over_r);
      const __m512d fz = _mm512_maskz_mul_pd(in, dz, f_over_r);
      fxi = _mm512_add_pd(fxi, fx), fyi = _mm512_add_pd(fyi, fy), fzi = _mm512_add_pd(fzi, fz);
      subtract_transposed(c.f, j, fx, fy, fz);
      if constexpr (kTally) {
        const __m512d e = _mm512_mul_pd(r6inv, _mm512_sub_pd(_mm512_mul_pd(lj3, r6inv), lj4));
        alignas(64) double pair[7][8];
        _mm512_store_pd(pair[0], _mm512_sub_pd(e, shift));
        _mm512_store_pd(pair[1], _mm512_mul_pd(dx, fx));
        _mm512_store_pd(pair[2], _mm512_mul_pd(dy, fy));
        _mm512_store_pd(pair[3], _mm512_mul_pd(dz, fz));
        _mm512_store_pd(pair[4], _mm512_mul_pd(dx, fy));
        _mm512_store_pd(pair[5], _mm512_mul_pd(dx, fz));
        _mm512_store_pd(pair[6], _mm512_mul_pd(dy, fz));
        add_tallies_in_lane_order(pair, in, energy, w);
      }
    }
    PaddedVec3& fi = c.f[i];
    fi.x += lane_sum(fxi);
    fi.y += lane_sum(fyi);
    fi.z += lane_sum(fzi);
  }
  if constexpr (kTally) virial += w;
  return energy;
}

}  // namespace
#endif

#ifdef DELI_LJ_AVX2
namespace {

// Four partners' positions (padded, 32 bytes each) as x, y and z vectors: lanes 0 and 2's
// halves (x y, then z pad) in one register and 1 and 3's in another, by 128-bit loads, then
// unpacked (no lane-crossing shuffle).
inline void load_transposed(const PaddedVec3* x, const std::int32_t* j, __m256d& px, __m256d& py,
                            __m256d& pz) {
  auto halves = [&](int a, int b, int half) {
    return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_load_pd(&x[j[a]].x + 2 * half)),
                                _mm_load_pd(&x[j[b]].x + 2 * half), 1);
  };
  const __m256d xy02 = halves(0, 2, 0), xy13 = halves(1, 3, 0);  // x0 y0 x2 y2, x1 y1 x3 y3
  const __m256d z02 = halves(0, 2, 1), z13 = halves(1, 3, 1);    // z0 - z2 -, z1 - z3 -
  px = _mm256_unpacklo_pd(xy02, xy13);
  py = _mm256_unpackhi_pd(xy02, xy13);
  pz = _mm256_unpacklo_pd(z02, z13);
}

// f[j[l]] -= (fx, fy, fz)[l] for the four lanes l: the transpose back, then one 256-bit load,
// subtract and store per lane (a lane without a pair subtracts +0: no change).
inline void subtract_transposed(PaddedVec3* f, const std::int32_t* j, __m256d fx, __m256d fy,
                                __m256d fz) {
  const __m256d xy02 = _mm256_unpacklo_pd(fx, fy);  // x0 y0 x2 y2
  const __m256d xy13 = _mm256_unpackhi_pd(fx, fy);
  const __m256d z02 = _mm256_unpacklo_pd(fz, _mm256_setzero_pd());  // z0 0 z2 0
  const __m256d z13 = _mm256_unpackhi_pd(fz, _mm256_setzero_pd());
  auto subtract = [&](int lane, __m256d v) {
    double* q = &f[j[lane]].x;
    _mm256_store_pd(q, _mm256_sub_pd(_mm256_load_pd(q), v));
  };
  subtract(0, _mm256_permute2f128_pd(xy02, z02, 0x20));
  subtract(1, _mm256_permute2f128_pd(xy13, z13, 0x20));
  subtract(2, _mm256_permute2f128_pd(xy02, z02, 0x31));
  subtract(3, _mm256_permute2f128_pd(xy13, z13, 0x31));
}

// Lanes 0-3 and 4-7's sum in lane_order_loop's order: ((0 + 4) + (2 + 6)) + ((1 + 5) + (3 + 7)).
inline double lane_sum(__m256d low, __m256d high) {
  const __m256d half = _mm256_add_pd(low, high);
  const __m128d quarter = _mm_add_pd(_mm256_castpd256_pd128(half), _mm256_extractf128_pd(half, 1));
  return _mm_cvtsd_f64(_mm_add_sd(quarter, _mm_unpackhi_pd(quarter, quarter)));
}

// All ones in the lanes first..first+3 below `count`.
inline __m256d lanes_below(std::size_t count, long long first) {
  return _mm256_castsi256_pd(
      _mm256_cmpgt_epi64(_mm256_set1_epi64x(static_cast<long long>(count)),
                         _mm256_setr_epi64x(first, first + 1, first + 2, first + 3)));
}

// The AVX-512 loop's vectors of eight partners as two halves of four (lanes 0-3 and 4-7), the
// same operations by lane and the same lane sums: the same bits.
template <bool kTally>
double loop(const LennardJones::Params& p, const VectorPairChunk& chunk, SymTensor& virial) {
  // A copy: the intrinsics' stores may alias anything, and through the reference every
  // iteration loaded the chunk's pointers again.
  const VectorPairChunk c = chunk;
  const __m256d cutoff2 = _mm256_set1_pd(p.cutoff2), one = _mm256_set1_pd(1.0);
  const __m256d lj1 = _mm256_set1_pd(p.lj1), lj2 = _mm256_set1_pd(p.lj2);
  const __m256d lj3 = _mm256_set1_pd(p.lj3), lj4 = _mm256_set1_pd(p.lj4);
  const __m256d shift = _mm256_set1_pd(p.energy_shift);
  // The image shifts by code, padded as the positions are, so that a vector's shifts load
  // and transpose as its partners' positions do; codes 27-31 (none) are zero.
  alignas(32) PaddedVec3 shift_table[32] = {};
  for (int code = 0; code < 27; ++code) {
    shift_table[code] = {c.shifts[code].x, c.shifts[code].y, c.shifts[code].z, 0.0};
  }
  const int zero_shift = zero_shift_code(c.shifts);
  std::uint64_t unshifted;
  std::memset(&unshifted, zero_shift, sizeof unshifted);
  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  double energy = 0.0;
  SymTensor w;
  alignas(32) std::int32_t tail[8];
  alignas(32) std::int32_t code_slots[8];
  for (std::int32_t i = c.first; i < c.last; ++i) {
    const __m256d xi = _mm256_set1_pd(c.x[i].x), yi = _mm256_set1_pd(c.x[i].y),
                  zi = _mm256_set1_pd(c.x[i].z);
    __m256d fxi[2] = {_mm256_setzero_pd(), _mm256_setzero_pd()}, fyi[2] = {fxi[0], fxi[0]},
            fzi[2] = {fxi[0], fxi[0]};
    const std::size_t end = c.ends ? c.ends[i] : c.offsets[i + 1];
    prefetch_partners_ahead(c, i);
    for (std::size_t k = c.offsets[i]; k < end; k += 8) {
      // As the AVX-512 loop: lanes past the list's end take particle i itself, outside
      // `lanes`, and subtract +0 from its force.
      const std::size_t left = end - k;
      const std::int32_t* j = c.list + k;
      std::uint64_t codes = unshifted;
      __m256d lanes[2] = {all, all};
      if (left < 8) {
        // The listed slots (a masked load reads nothing past the list's end), i elsewhere.
        const __m256i listed = _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(left)),
                                                  _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        _mm256_store_si256(
            reinterpret_cast<__m256i*>(tail),
            _mm256_blendv_epi8(_mm256_set1_epi32(i), _mm256_maskload_epi32(j, listed), listed));
        j = tail;
        // The lanes past the end take the last listed code: a vector whose listed lanes
        // share one code still counts as one shift.
        std::memset(&codes, c.codes[k + left - 1], sizeof codes);
        std::memcpy(&codes, c.codes + k, left);
        lanes[0] = lanes_below(left, 0);
        lanes[1] = lanes_below(left, 4);
      } else {
        std::memcpy(&codes, c.codes + k, sizeof codes);
      }
      // Most vectors cross no periodic boundary: every lane's code the unshifted image's.
      const bool shifted = codes != unshifted;
      // The list gives a particle's partners through each shift together (the stencil's
      // order): a shifted vector's lanes nearly always share one, whose components are then
      // broadcast rather than loaded lane by lane (with the stencil's order, LJ 32000's pair
      // phase 0.94x).
      bool mixed = false;
      __m256d one_sx = _mm256_setzero_pd(), one_sy = one_sx, one_sz = one_sx;
      if (shifted) {
        const std::uint64_t first_code = codes & 0xffu;
        mixed = codes != first_code * 0x0101010101010101ULL;
        if (mixed) {
          _mm256_store_si256(
              reinterpret_cast<__m256i*>(code_slots),
              _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(codes))));
        } else {
          one_sx = _mm256_broadcast_sd(&shift_table[first_code].x);
          one_sy = _mm256_broadcast_sd(&shift_table[first_code].y);
          one_sz = _mm256_broadcast_sd(&shift_table[first_code].z);
        }
      }
      [[maybe_unused]] alignas(32) double pair[7][8];
      [[maybe_unused]] unsigned in_lanes = 0;
      // Unrolled: the halves' accumulators then stay in registers.
#pragma GCC unroll 2
      for (int h = 0; h < 2; ++h) {
        // A partial vector of at most four lanes has nothing in its second half.
        if (h == 1 && left <= 4) break;
        __m256d xj, yj, zj;
        load_transposed(c.x, j + 4 * h, xj, yj, zj);
        __m256d dx = _mm256_sub_pd(xi, xj), dy = _mm256_sub_pd(yi, yj), dz = _mm256_sub_pd(zi, zj);
        if (shifted) {
          __m256d sx = one_sx, sy = one_sy, sz = one_sz;
          if (mixed) load_transposed(shift_table, code_slots + 4 * h, sx, sy, sz);
          dx = _mm256_sub_pd(dx, sx);
          dy = _mm256_sub_pd(dy, sy);
          dz = _mm256_sub_pd(dz, sz);
        }
        const __m256d r2 = _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
        const __m256d in = _mm256_and_pd(lanes[h], _mm256_cmp_pd(r2, cutoff2, _CMP_LT_OQ));
        // Lanes outside take r^2 = 1 (no infinity from a lane at r = 0), their results +0.
        const __m256d r2inv = _mm256_div_pd(one, _mm256_blendv_pd(one, r2, in));
        const __m256d r6inv = _mm256_mul_pd(_mm256_mul_pd(r2inv, r2inv), r2inv);
        const __m256d f_over_r = _mm256_mul_pd(
            _mm256_mul_pd(r6inv, _mm256_sub_pd(_mm256_mul_pd(lj1, r6inv), lj2)), r2inv);
        const __m256d fx = _mm256_and_pd(in, _mm256_mul_pd(dx, f_over_r));
        const __m256d fy = _mm256_and_pd(in, _mm256_mul_pd(dy, f_over_r));
        const __m256d fz = _mm256_and_pd(in, _mm256_mul_pd(dz, f_over_r));
        fxi[h] = _mm256_add_pd(fxi[h], fx);
        fyi[h] = _mm256_add_pd(fyi[h], fy);
        fzi[h] = _mm256_add_pd(fzi[h], fz);
        subtract_transposed(c.f, j + 4 * h, fx, fy, fz);
        if constexpr (kTally) {
          const __m256d e = _mm256_mul_pd(r6inv, _mm256_sub_pd(_mm256_mul_pd(lj3, r6inv), lj4));
          _mm256_store_pd(pair[0] + 4 * h, _mm256_sub_pd(e, shift));
          _mm256_store_pd(pair[1] + 4 * h, _mm256_mul_pd(dx, fx));
          _mm256_store_pd(pair[2] + 4 * h, _mm256_mul_pd(dy, fy));
          _mm256_store_pd(pair[3] + 4 * h, _mm256_mul_pd(dz, fz));
          _mm256_store_pd(pair[4] + 4 * h, _mm256_mul_pd(dx, fy));
          _mm256_store_pd(pair[5] + 4 * h, _mm256_mul_pd(dx, fz));
          _mm256_store_pd(pair[6] + 4 * h, _mm256_mul_pd(dy, fz));
          in_lanes |= static_cast<unsigned>(_mm256_movemask_pd(in)) << (4 * h);
        }
      }
      if constexpr (kTally) add_tallies_in_lane_order(pair, in_lanes, energy, w);
    }
    // One 256-bit add (the pad adds +0): the partners' subtractions store f[i] whole, and a
    // later one's load of it would not be forwarded from three 8-byte stores.
    double* fi = &c.f[i].x;
    _mm256_store_pd(fi,
                    _mm256_add_pd(_mm256_load_pd(fi),
                                  _mm256_setr_pd(lane_sum(fxi[0], fxi[1]), lane_sum(fyi[0], fyi[1]),
                                                 lane_sum(fzi[0], fzi[1]), 0.0)));
  }
  if constexpr (kTally) virial += w;
  return energy;
}

}  // namespace
#endif

#if defined(DELI_LJ_AVX512) || defined(DELI_LJ_AVX2)
bool LennardJones::vector_loop_built() {
  return true;
}

double LennardJones::vector_loop(const Params& p, const VectorPairChunk& chunk, bool tally,
                                 SymTensor& virial) {
  return tally ? loop<true>(p, chunk, virial) : loop<false>(p, chunk, virial);
}
#else
bool LennardJones::vector_loop_built() {
  return false;
}

double LennardJones::vector_loop(const Params& p, const VectorPairChunk& chunk, bool tally,
                                 SymTensor& virial) {
  return lane_order_loop(p, chunk, tally, virial);
}
#endif

// The vector loop's sums one pair at a time: a particle's pairs added to eight partial sums
// by their place in its list modulo 8, those added as lane_sum() adds the lanes. Pairs
// outside the cutoff add nothing here and +0 there: a partial sum starts at +0 and never
// becomes -0, so adding +0 changes nothing. Two passes, as PairForce's scalar loop, so
// that the branch on the cutoff is not taken per pair.
double LennardJones::lane_order_loop(const Params& p, const VectorPairChunk& c, bool tally,
                                     SymTensor& virial) {
  struct Inside {
    std::int32_t j;
    int lane;
    double dx, dy, dz, r2;
  };
  thread_local std::vector<Inside> inside;
  double energy = 0.0;
  SymTensor w;
  for (std::int32_t i = c.first; i < c.last; ++i) {
    const PaddedVec3 xi = c.x[i];
    const std::size_t begin = c.offsets[i], count = (c.ends ? c.ends[i] : c.offsets[i + 1]) - begin;
    if (inside.size() < count + 1) inside.resize(2 * count + 1);
    std::size_t kept = 0;
    for (std::size_t k = begin; k < begin + count; ++k) {
      const std::int32_t j = c.list[k];
      const Vec3& s = c.shifts[c.codes[k]];
      // Subtracting a zero shift, as the vector loop skips it, changes nothing.
      const double dx = (xi.x - c.x[j].x) - s.x, dy = (xi.y - c.x[j].y) - s.y,
                   dz = (xi.z - c.x[j].z) - s.z;
      const double r2 = dx * dx + dy * dy + dz * dz;
      inside[kept] = {j, static_cast<int>((k - begin) % 8), dx, dy, dz, r2};
      kept += r2 < p.cutoff2;
    }
    double ax[8] = {}, ay[8] = {}, az[8] = {};
    for (std::size_t k = 0; k < kept; ++k) {
      const Inside& q = inside[k];
      double f_over_r, e;
      evaluate(p, q.r2, f_over_r, e);
      const double fx = q.dx * f_over_r, fy = q.dy * f_over_r, fz = q.dz * f_over_r;
      ax[q.lane] += fx, ay[q.lane] += fy, az[q.lane] += fz;
      c.f[q.j].x -= fx, c.f[q.j].y -= fy, c.f[q.j].z -= fz;
      if (tally) {
        energy += e - p.energy_shift;
        w.xx += q.dx * fx, w.yy += q.dy * fy, w.zz += q.dz * fz;
        w.xy += q.dx * fy, w.xz += q.dx * fz, w.yz += q.dy * fz;
      }
    }
    auto sum = [](const double* a) {
      return ((a[0] + a[4]) + (a[2] + a[6])) + ((a[1] + a[5]) + (a[3] + a[7]));
    };
    c.f[i].x += sum(ax), c.f[i].y += sum(ay), c.f[i].z += sum(az);
  }
  if (tally) virial += w;
  return energy;
}

#if defined(DELI_LJ_AVX512) && defined(__AVX512DQ__)
namespace {

// Box::round_to_integer by lane: half away from zero where |x| < 2^52 (the conversion
// truncates, as static_cast does), x itself elsewhere (NaN too).
inline __m512d round_to_integer(__m512d x) {
  const __m512i sign = _mm512_set1_epi64(static_cast<long long>(0x8000000000000000ULL));
  const __m512i bits = _mm512_castpd_si512(x);
  const __m512d magnitude = _mm512_castsi512_pd(_mm512_andnot_si512(sign, bits));
  const __m512d half = _mm512_castsi512_pd(
      _mm512_or_si512(_mm512_castpd_si512(_mm512_set1_pd(0.5)), _mm512_and_si512(sign, bits)));
  const __mmask8 convertible = _mm512_cmp_pd_mask(magnitude, _mm512_set1_pd(0x1p52), _CMP_LT_OQ);
  const __m512d whole = _mm512_cvtepi64_pd(_mm512_cvttpd_epi64(_mm512_add_pd(x, half)));
  return _mm512_mask_blend_pd(convertible, x, whole);
}

// Component `axis` of the partners' Vec3s (lanes outside `lanes` get 0).
inline __m512d gather_axis(const Vec3* v, __m512i index3, __mmask8 lanes, int axis) {
  return _mm512_mask_i64gather_pd(_mm512_setzero_pd(), lanes, index3,
                                  reinterpret_cast<const double*>(v) + axis, 8);
}

}  // namespace

bool LennardJones::curvature_loop_built() {
  return true;
}

// PairForce::curvature_term's operations in its order by lane (no contraction: the build
// has -ffp-contract=off and these are separate multiplies and adds), then the lanes added
// to the sum one at a time in list order.
double LennardJones::curvature_loop(const Params& p, const CurvatureChunk& c) {
  const __m512d cutoff2 = _mm512_set1_pd(p.cutoff2);
  const __m512d lj1 = _mm512_set1_pd(p.lj1), lj2 = _mm512_set1_pd(p.lj2);
  const __m512d lj1_13 = _mm512_set1_pd(13.0 * p.lj1), lj2_7 = _mm512_set1_pd(7.0 * p.lj2);
  const __m512d one = _mm512_set1_pd(1.0);
  const __m512d period[3] = {_mm512_set1_pd(c.period.x), _mm512_set1_pd(c.period.y),
                             _mm512_set1_pd(c.period.z)};
  const __m512d inverse[3] = {_mm512_set1_pd(c.inverse_period.x),
                              _mm512_set1_pd(c.inverse_period.y),
                              _mm512_set1_pd(c.inverse_period.z)};
  double sum = 0.0;
  alignas(64) double terms[8];
  for (std::size_t i = c.first; i < c.last; ++i) {
    const __m512d xi[3] = {_mm512_set1_pd(c.x[i].x), _mm512_set1_pd(c.x[i].y),
                           _mm512_set1_pd(c.x[i].z)};
    const __m512d vi[3] = {_mm512_set1_pd(c.v[i].x), _mm512_set1_pd(c.v[i].y),
                           _mm512_set1_pd(c.v[i].z)};
    const std::size_t end = c.ends ? c.ends[i] : c.offsets[i + 1];
    for (std::size_t k = c.offsets[i]; k < end; k += 8) {
      const std::size_t count = end - k < 8 ? end - k : 8;
      const __mmask8 lanes = static_cast<__mmask8>((1u << count) - 1u);
      const __m512i j = _mm512_cvtepi32_epi64(_mm256_maskz_loadu_epi32(lanes, c.list + k));
      const __m512i j3 = _mm512_add_epi64(_mm512_slli_epi64(j, 1), j);
      __m512d d[3], w[3];
      for (int a = 0; a < 3; ++a) {
        d[a] = _mm512_sub_pd(xi[a], gather_axis(c.x, j3, lanes, a));
        d[a] = _mm512_sub_pd(
            d[a], _mm512_mul_pd(period[a], round_to_integer(_mm512_mul_pd(d[a], inverse[a]))));
        w[a] = _mm512_sub_pd(vi[a], gather_axis(c.v, j3, lanes, a));
      }
      const __m512d r2 =
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(d[0], d[0]), _mm512_mul_pd(d[1], d[1])),
                        _mm512_mul_pd(d[2], d[2]));
      // In reach as the scalar term decides it: not r2 >= cutoff2.
      const __mmask8 inside = _mm512_mask_cmp_pd_mask(lanes, r2, cutoff2, _CMP_NGE_UQ);
      const __m512d r2inv = _mm512_div_pd(one, r2);
      const __m512d r6inv = _mm512_mul_pd(_mm512_mul_pd(r2inv, r2inv), r2inv);
      const __m512d f_over_r =
          _mm512_mul_pd(_mm512_mul_pd(r6inv, _mm512_sub_pd(_mm512_mul_pd(lj1, r6inv), lj2)), r2inv);
      const __m512d curvature = _mm512_mul_pd(
          _mm512_mul_pd(r6inv, _mm512_sub_pd(_mm512_mul_pd(lj1_13, r6inv), lj2_7)), r2inv);
      const __m512d along =
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(d[0], w[0]), _mm512_mul_pd(d[1], w[1])),
                        _mm512_mul_pd(d[2], w[2]));
      const __m512d along2 = _mm512_div_pd(_mm512_mul_pd(along, along), r2);
      const __m512d w2 =
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(w[0], w[0]), _mm512_mul_pd(w[1], w[1])),
                        _mm512_mul_pd(w[2], w[2]));
      const __m512d term = _mm512_sub_pd(_mm512_mul_pd(curvature, along2),
                                         _mm512_mul_pd(f_over_r, _mm512_sub_pd(w2, along2)));
      // Out of reach: the scalar term's +0, which leaves the sum as it is.
      _mm512_store_pd(terms, _mm512_maskz_mov_pd(inside, term));
      for (std::size_t l = 0; l < count; ++l) sum += terms[l];
    }
  }
  return sum;
}
#elif defined(DELI_LJ_AVX2)
namespace {

// Box::round_to_integer by lane: half away from zero where |x| < 2^52, x itself elsewhere
// (NaN too). Truncated as the conversion truncates; + 0 turns a -0 (from -0.5 < x < 0) into
// the conversion's +0.
inline __m256d round_to_integer(__m256d x) {
  const __m256d sign = _mm256_set1_pd(-0.0);
  const __m256d half = _mm256_or_pd(_mm256_set1_pd(0.5), _mm256_and_pd(sign, x));
  const __m256d convertible =
      _mm256_cmp_pd(_mm256_andnot_pd(sign, x), _mm256_set1_pd(0x1p52), _CMP_LT_OQ);
  const __m256d whole =
      _mm256_add_pd(_mm256_round_pd(_mm256_add_pd(x, half), _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC),
                    _mm256_setzero_pd());
  return _mm256_blendv_pd(x, whole, convertible);
}

}  // namespace

bool LennardJones::curvature_loop_built() {
  return true;
}

// The AVX-512 curvature loop's operations by lane in vectors of four (partners' components
// gathered), the lanes added to the sum one at a time in list order.
double LennardJones::curvature_loop(const Params& p, const CurvatureChunk& chunk) {
  const CurvatureChunk c = chunk;  // as in loop(): not reloaded after each store
  const __m256d cutoff2 = _mm256_set1_pd(p.cutoff2);
  const __m256d lj1 = _mm256_set1_pd(p.lj1), lj2 = _mm256_set1_pd(p.lj2);
  const __m256d lj1_13 = _mm256_set1_pd(13.0 * p.lj1), lj2_7 = _mm256_set1_pd(7.0 * p.lj2);
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d period[3] = {_mm256_set1_pd(c.period.x), _mm256_set1_pd(c.period.y),
                             _mm256_set1_pd(c.period.z)};
  const __m256d inverse[3] = {_mm256_set1_pd(c.inverse_period.x),
                              _mm256_set1_pd(c.inverse_period.y),
                              _mm256_set1_pd(c.inverse_period.z)};
  double sum = 0.0;
  alignas(32) double terms[4];
  for (std::size_t i = c.first; i < c.last; ++i) {
    const __m256d xi[3] = {_mm256_set1_pd(c.x[i].x), _mm256_set1_pd(c.x[i].y),
                           _mm256_set1_pd(c.x[i].z)};
    const __m256d vi[3] = {_mm256_set1_pd(c.v[i].x), _mm256_set1_pd(c.v[i].y),
                           _mm256_set1_pd(c.v[i].z)};
    const std::size_t end = c.ends ? c.ends[i] : c.offsets[i + 1];
    for (std::size_t k = c.offsets[i]; k < end; k += 4) {
      const std::size_t count = end - k < 4 ? end - k : 4;
      const __m128i listed =
          _mm_cmpgt_epi32(_mm_set1_epi32(static_cast<int>(count)), _mm_setr_epi32(0, 1, 2, 3));
      const __m256d lanes = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(listed));
      const __m128i j = _mm_maskload_epi32(c.list + k, listed);
      const __m128i j3 = _mm_add_epi32(_mm_slli_epi32(j, 1), j);
      auto gather = [&](const Vec3* v, int axis) {
        return _mm256_mask_i32gather_pd(_mm256_setzero_pd(),
                                        reinterpret_cast<const double*>(v) + axis, j3, lanes, 8);
      };
      __m256d d[3], w[3];
      for (int a = 0; a < 3; ++a) {
        d[a] = _mm256_sub_pd(xi[a], gather(c.x, a));
        d[a] = _mm256_sub_pd(
            d[a], _mm256_mul_pd(period[a], round_to_integer(_mm256_mul_pd(d[a], inverse[a]))));
        w[a] = _mm256_sub_pd(vi[a], gather(c.v, a));
      }
      const __m256d r2 =
          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
                        _mm256_mul_pd(d[2], d[2]));
      // In reach as the scalar term decides it: not r2 >= cutoff2.
      const __m256d inside = _mm256_and_pd(lanes, _mm256_cmp_pd(r2, cutoff2, _CMP_NGE_UQ));
      const __m256d r2inv = _mm256_div_pd(one, r2);
      const __m256d r6inv = _mm256_mul_pd(_mm256_mul_pd(r2inv, r2inv), r2inv);
      const __m256d f_over_r =
          _mm256_mul_pd(_mm256_mul_pd(r6inv, _mm256_sub_pd(_mm256_mul_pd(lj1, r6inv), lj2)), r2inv);
      const __m256d curvature = _mm256_mul_pd(
          _mm256_mul_pd(r6inv, _mm256_sub_pd(_mm256_mul_pd(lj1_13, r6inv), lj2_7)), r2inv);
      const __m256d along =
          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(d[0], w[0]), _mm256_mul_pd(d[1], w[1])),
                        _mm256_mul_pd(d[2], w[2]));
      const __m256d along2 = _mm256_div_pd(_mm256_mul_pd(along, along), r2);
      const __m256d w2 =
          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(w[0], w[0]), _mm256_mul_pd(w[1], w[1])),
                        _mm256_mul_pd(w[2], w[2]));
      const __m256d term = _mm256_sub_pd(_mm256_mul_pd(curvature, along2),
                                         _mm256_mul_pd(f_over_r, _mm256_sub_pd(w2, along2)));
      // Out of reach: the scalar term's +0, which leaves the sum as it is.
      _mm256_store_pd(terms, _mm256_and_pd(inside, term));
      for (std::size_t l = 0; l < count; ++l) sum += terms[l];
    }
  }
  return sum;
}
#else
bool LennardJones::curvature_loop_built() {
  return false;
}

double LennardJones::curvature_loop(const Params&, const CurvatureChunk&) {
  throw std::logic_error("LennardJones::curvature_loop: not built (check curvature_loop_built)");
}
#endif

}  // namespace deli
