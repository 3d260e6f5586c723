#include <cstring>

#include "pair/lennard_jones.hpp"

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
#include <immintrin.h>
#define DELI_LJ_AVX512 1
// GCC 12 warns that the intrinsics' own _mm512_undefined_pd() is (or may be) used
// uninitialized inside the extracts and reductions (a false positive: GCC PR 105593).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace deli {

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

template <bool kTally>
double loop(const LennardJones::Params& p, const VectorPairChunk& c, SymTensor& virial) {
  const __m512d cutoff2 = _mm512_set1_pd(p.cutoff2), one = _mm512_set1_pd(1.0);
  const __m512d lj1 = _mm512_set1_pd(p.lj1), lj2 = _mm512_set1_pd(p.lj2);
  const __m512d lj3 = _mm512_set1_pd(p.lj3), lj4 = _mm512_set1_pd(p.lj4);
  const __m512d shift = _mm512_set1_pd(p.energy_shift);
  const ShiftTable sx(c.shifts, 0), sy(c.shifts, 1), sz(c.shifts, 2);
  // The code of a zero shift (the list's numbering, not assumed here; 255, never a code,
  // if there were none): vectors whose lanes all have it skip the shift.
  int zero_shift = 255;
  for (int code = 26; code >= 0; --code) {
    const Vec3& s = c.shifts[code];
    if (s.x == 0.0 && s.y == 0.0 && s.z == 0.0) zero_shift = code;
  }
  const __m128i unshifted = _mm_set1_epi8(static_cast<char>(zero_shift));
  double energy = 0.0;
  SymTensor w;
  alignas(32) std::int32_t tail[8];
  for (std::int32_t i = c.first; i < c.last; ++i) {
    const __m512d xi = _mm512_set1_pd(c.x[i].x), yi = _mm512_set1_pd(c.x[i].y),
                  zi = _mm512_set1_pd(c.x[i].z);
    __m512d fxi = _mm512_setzero_pd(), fyi = fxi, fzi = fxi;
    const std::size_t end = c.offsets[i + 1];
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
        // Energy and virial pair by pair in list order, as the scalar loop adds them: the
        // same sums bit for bit (a lattice's equal terms round alike, and eight lane sums
        // moved a 32000-atom energy by 3.5e-12 of itself from the other engines', whose
        // sums are in this order too). Tallies are rare steps: the cost does not show.
        const __m512d e = _mm512_mul_pd(r6inv, _mm512_sub_pd(_mm512_mul_pd(lj3, r6inv), lj4));
        alignas(64) double pair[7][8];
        _mm512_store_pd(pair[0], _mm512_sub_pd(e, shift));
        _mm512_store_pd(pair[1], _mm512_mul_pd(dx, fx));
        _mm512_store_pd(pair[2], _mm512_mul_pd(dy, fy));
        _mm512_store_pd(pair[3], _mm512_mul_pd(dz, fz));
        _mm512_store_pd(pair[4], _mm512_mul_pd(dx, fy));
        _mm512_store_pd(pair[5], _mm512_mul_pd(dx, fz));
        _mm512_store_pd(pair[6], _mm512_mul_pd(dy, fz));
        for (unsigned m = in; m != 0; m &= m - 1) {
          const int l = __builtin_ctz(m);
          energy += pair[0][l];
          w.xx += pair[1][l], w.yy += pair[2][l], w.zz += pair[3][l];
          w.xy += pair[4][l], w.xz += pair[5][l], w.yz += pair[6][l];
        }
      }
    }
    PaddedVec3& fi = c.f[i];
    fi.x += _mm512_reduce_add_pd(fxi);
    fi.y += _mm512_reduce_add_pd(fyi);
    fi.z += _mm512_reduce_add_pd(fzi);
  }
  if constexpr (kTally) virial += w;
  return energy;
}

}  // namespace

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

// Never called by PairForce in this build (vector_loop_built() is false); the definition,
// pair by pair, for any other caller.
double LennardJones::vector_loop(const Params& p, const VectorPairChunk& c, bool tally,
                                 SymTensor& virial) {
  double energy = 0.0;
  for (std::int32_t i = c.first; i < c.last; ++i) {
    for (std::size_t k = c.offsets[i]; k < c.offsets[i + 1]; ++k) {
      const std::int32_t j = c.list[k];
      const Vec3& s = c.shifts[c.codes[k]];
      const Vec3 d{c.x[i].x - c.x[j].x - s.x, c.x[i].y - c.x[j].y - s.y, c.x[i].z - c.x[j].z - s.z};
      const double r2 = norm2(d);
      if (!(r2 < p.cutoff2)) continue;
      double f_over_r, e;
      evaluate(p, r2, f_over_r, e);
      const Vec3 f = d * f_over_r;
      c.f[i].x += f.x, c.f[i].y += f.y, c.f[i].z += f.z;
      c.f[j].x -= f.x, c.f[j].y -= f.y, c.f[j].z -= f.z;
      if (tally) {
        energy += e - p.energy_shift;
        virial.add_outer(d, f);
      }
    }
  }
  return energy;
}
#endif

}  // namespace deli
