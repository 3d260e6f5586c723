#include "thermostats/normal_triples.hpp"

#include <cmath>

#include "thermostats/polar_log.hpp"

#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
#include <immintrin.h>
#define DELI_NORMALS_AVX512 1
// GCC 12 warns that the intrinsics' own _mm512_undefined_*() is (or may be) used
// uninitialized inside the conversions (a false positive: GCC PR 105593).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#elif defined(__AVX2__)
#include <immintrin.h>
#define DELI_NORMALS_AVX2 1
#endif

namespace deli {

void normal_triples_by_stream(std::uint64_t seed, const PhiloxCounter* start, std::size_t count,
                              Vec3* out) {
  for (std::size_t k = 0; k < count; ++k) {
    RandomStream random(seed, start[k]);
    const double x = random.normal(), y = random.normal(), z = random.normal();
    out[k] = {x, y, z};
  }
}

#ifdef DELI_NORMALS_AVX512
namespace {

// Philox4x32-10 (philox4x32_10) on eight counters: each 32-bit word in the low half of a
// 64-bit lane, so that one vpmuludq gives the round's full 64-bit products.
struct Block8 {
  __m512i w[4];
};

Block8 philox8(Block8 c, std::uint32_t key0, std::uint32_t key1) {
  const __m512i low = _mm512_set1_epi64(0xffffffffLL);
  const __m512i multiplier0 = _mm512_set1_epi64(0xD2511F53),
                multiplier1 = _mm512_set1_epi64(0xCD9E8D57);
  for (int round = 0; round < 10; ++round) {
    if (round > 0) key0 += 0x9E3779B9u, key1 += 0xBB67AE85u;
    const __m512i p0 = _mm512_mul_epu32(multiplier0, c.w[0]);
    const __m512i p1 = _mm512_mul_epu32(multiplier1, c.w[2]);
    const __m512i k0 = _mm512_set1_epi64(key0), k1 = _mm512_set1_epi64(key1);
    c.w[0] = _mm512_xor_si512(_mm512_xor_si512(_mm512_srli_epi64(p1, 32), c.w[1]), k0);
    c.w[1] = _mm512_and_si512(p1, low);
    c.w[2] = _mm512_xor_si512(_mm512_xor_si512(_mm512_srli_epi64(p0, 32), c.w[3]), k1);
    c.w[3] = _mm512_and_si512(p0, low);
  }
  return c;
}

// RandomStream::symmetric_uniform of a word: (int32 + 0.5) 2^-31, exact in doubles.
__m512d symmetric(__m512i word) {
  const __m256i as_int = _mm512_cvtepi64_epi32(word);  // the low 32 bits, as int32
  return _mm512_mul_pd(_mm512_add_pd(_mm512_cvtepi32_pd(as_int), _mm512_set1_pd(0.5)),
                       _mm512_set1_pd(0x1.0p-31));
}

// The polar method's factor sqrt(-2 log(s) / s), in RandomStream::normal's operations; the
// logarithm lane by lane (polar_log, its bits).
__m512d polar_factor(__m512d s) {
  alignas(64) double lanes[8];
  _mm512_store_pd(lanes, s);
  for (double& x : lanes) x = polar_log(x);
  const __m512d log_s = _mm512_load_pd(lanes);
  return _mm512_sqrt_pd(_mm512_div_pd(_mm512_mul_pd(_mm512_set1_pd(-2.0), log_s), s));
}

}  // namespace

bool normal_triples_vectorised() {
  return true;
}

// Blocks drawn by vector per stream: with three (six pairs), 0.2 % of streams accept fewer
// than two pairs and are drawn by RandomStream (3 % with two blocks, then 2.5 % of a Langevin
// melt's samples).
constexpr int kBlocks = 3;

void normal_triples(std::uint64_t seed, const PhiloxCounter* start, std::size_t count, Vec3* out) {
  const auto key0 = static_cast<std::uint32_t>(seed), key1 = static_cast<std::uint32_t>(seed >> 32);
  std::size_t k = 0;
  for (; k + 8 <= count; k += 8) {
    alignas(64) std::uint64_t word[4][8];
    for (int l = 0; l < 8; ++l) {
      for (int q = 0; q < 4; ++q) word[q][l] = start[k + l][q];
    }
    Block8 counter;
    for (int q = 0; q < 4; ++q) counter.w[q] = _mm512_load_si512(word[q]);
    // The stream's first three blocks: the counter's last word plus 0, 1 and 2
    // (RandomStream::refill), in 32 bits.
    Block8 block[kBlocks];
    for (int b = 0; b < kBlocks; ++b) {
      block[b] = philox8(counter, key0, key1);
      counter.w[3] = _mm512_and_si512(_mm512_add_epi64(counter.w[3], _mm512_set1_epi64(1)),
                                      _mm512_set1_epi64(0xffffffffLL));
    }
    // Its first pairs (u, v), two per block, and whether each is accepted (s < 1).
    constexpr int pairs = 2 * kBlocks;
    __m512d u[pairs], v[pairs], s[pairs];
    __mmask8 accepted[pairs];
    for (int q = 0; q < pairs; ++q) {
      const Block8& b = block[q / 2];
      u[q] = symmetric(b.w[2 * (q % 2)]);
      v[q] = symmetric(b.w[2 * (q % 2) + 1]);
      s[q] = _mm512_add_pd(_mm512_mul_pd(u[q], u[q]), _mm512_mul_pd(v[q], v[q]));
      accepted[q] = _mm512_cmp_pd_mask(s[q], _mm512_set1_pd(1.0), _CMP_LT_OQ);
    }
    // The first accepted pair, then the next accepted one after it; lanes with fewer than two
    // accepted among those pairs are drawn by RandomStream below.
    __m512d u1 = u[0], v1 = v[0], s1 = s[0];
    __m512d u2 = u[0], s2 = s[0];
    __mmask8 none_before = 0xff;  // no accepted pair among those looked at so far
    __mmask8 one_before = 0;      // exactly one
    __mmask8 second_found = 0;
    for (int q = 0; q < pairs; ++q) {
      const __mmask8 first_here = none_before & accepted[q];
      const __mmask8 second_here = one_before & accepted[q];
      u1 = _mm512_mask_blend_pd(first_here, u1, u[q]);
      v1 = _mm512_mask_blend_pd(first_here, v1, v[q]);
      s1 = _mm512_mask_blend_pd(first_here, s1, s[q]);
      u2 = _mm512_mask_blend_pd(second_here, u2, u[q]);
      s2 = _mm512_mask_blend_pd(second_here, s2, s[q]);
      second_found |= second_here;
      one_before = (one_before & ~accepted[q]) | first_here;
      none_before &= ~accepted[q];
    }
    const __m512d f1 = polar_factor(s1), f2 = polar_factor(s2);
    alignas(64) double x[8], y[8], z[8];
    _mm512_store_pd(x, _mm512_mul_pd(u1, f1));
    _mm512_store_pd(y, _mm512_mul_pd(v1, f1));
    _mm512_store_pd(z, _mm512_mul_pd(u2, f2));
    for (int l = 0; l < 8; ++l) {
      if (second_found >> l & 1) {
        out[k + l] = {x[l], y[l], z[l]};
      } else {
        normal_triples_by_stream(seed, start + k + l, 1, out + k + l);
      }
    }
  }
  normal_triples_by_stream(seed, start + k, count - k, out + k);
}
#elif defined(DELI_NORMALS_AVX2)
namespace {

// The AVX-512 form's Philox4x32-10 on four counters: each 32-bit word in the low half of a
// 64-bit lane.
struct Block4 {
  __m256i w[4];
};

Block4 philox4(Block4 c, std::uint32_t key0, std::uint32_t key1) {
  const __m256i low = _mm256_set1_epi64x(0xffffffffLL);
  const __m256i multiplier0 = _mm256_set1_epi64x(0xD2511F53),
                multiplier1 = _mm256_set1_epi64x(0xCD9E8D57);
  for (int round = 0; round < 10; ++round) {
    if (round > 0) key0 += 0x9E3779B9u, key1 += 0xBB67AE85u;
    const __m256i p0 = _mm256_mul_epu32(multiplier0, c.w[0]);
    const __m256i p1 = _mm256_mul_epu32(multiplier1, c.w[2]);
    const __m256i k0 = _mm256_set1_epi64x(key0), k1 = _mm256_set1_epi64x(key1);
    c.w[0] = _mm256_xor_si256(_mm256_xor_si256(_mm256_srli_epi64(p1, 32), c.w[1]), k0);
    c.w[1] = _mm256_and_si256(p1, low);
    c.w[2] = _mm256_xor_si256(_mm256_xor_si256(_mm256_srli_epi64(p0, 32), c.w[3]), k1);
    c.w[3] = _mm256_and_si256(p0, low);
  }
  return c;
}

// RandomStream::symmetric_uniform of a word: (int32 + 0.5) 2^-31, exact in doubles.
__m256d symmetric(__m256i word) {
  const __m128i as_int = _mm256_castsi256_si128(
      _mm256_permutevar8x32_epi32(word, _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6)));
  return _mm256_mul_pd(_mm256_add_pd(_mm256_cvtepi32_pd(as_int), _mm256_set1_pd(0.5)),
                       _mm256_set1_pd(0x1.0p-31));
}

// polar_log on four lanes: its operations in its order, the same bits. Its exponent k as a
// double exactly: 2^52 + (k + 2048) from its bits, less 2^52 + 2048.
__m256d polar_log4(__m256d x) {
  using namespace polar_log_constants;
  auto integer = [](long long v) { return _mm256_set1_epi64x(v); };
  auto number = [](double v) { return _mm256_set1_pd(v); };
  const __m256i bits = _mm256_castpd_si256(x);
  const __m256i high = _mm256_and_si256(_mm256_srli_epi64(bits, 32), integer(0x000fffff));
  const __m256i half =
      _mm256_and_si256(_mm256_add_epi64(high, integer(0x95f64)), integer(0x100000));
  const __m256i scaled_bits = _mm256_or_si256(
      _mm256_slli_epi64(_mm256_or_si256(high, _mm256_xor_si256(half, integer(0x3ff00000))), 32),
      _mm256_and_si256(bits, integer(0xffffffff)));
  const __m256i k_plus = _mm256_add_epi64(
      _mm256_add_epi64(_mm256_and_si256(_mm256_srli_epi64(bits, 52), integer(0x7ff)),
                       integer(2048 - 1023)),
      _mm256_srli_epi64(half, 20));
  const __m256d dk =
      _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(k_plus, integer(0x4330000000000000))),
                    number(0x1.0p52 + 2048.0));
  const __m256d f = _mm256_sub_pd(_mm256_castsi256_pd(scaled_bits), number(1.0));
  const __m256d k_hi = _mm256_mul_pd(dk, number(ln2_hi));
  const __m256d k_lo = _mm256_mul_pd(dk, number(ln2_lo));
  // |f| < 2^-20.
  const __m256d r_tiny = _mm256_mul_pd(_mm256_mul_pd(f, f),
                                       _mm256_sub_pd(number(0.5), _mm256_mul_pd(number(third), f)));
  const __m256d tiny_log = _mm256_sub_pd(k_hi, _mm256_sub_pd(_mm256_sub_pd(r_tiny, k_lo), f));
  const __m256d s = _mm256_div_pd(f, _mm256_add_pd(number(2.0), f));
  const __m256d z = _mm256_mul_pd(s, s);
  const __m256d w = _mm256_mul_pd(z, z);
  const __m256d t1 = _mm256_mul_pd(
      w,
      _mm256_add_pd(number(lg2),
                    _mm256_mul_pd(w, _mm256_add_pd(number(lg4), _mm256_mul_pd(w, number(lg6))))));
  const __m256d t2 = _mm256_mul_pd(
      z,
      _mm256_add_pd(
          number(lg1),
          _mm256_mul_pd(
              w, _mm256_add_pd(number(lg3),
                               _mm256_mul_pd(w, _mm256_add_pd(number(lg5),
                                                              _mm256_mul_pd(w, number(lg7))))))));
  const __m256d r = _mm256_add_pd(t2, t1);
  const __m256d hfsq = _mm256_mul_pd(_mm256_mul_pd(number(0.5), f), f);
  const __m256d middle_log = _mm256_sub_pd(
      k_hi,
      _mm256_sub_pd(
          _mm256_sub_pd(hfsq, _mm256_add_pd(_mm256_mul_pd(s, _mm256_add_pd(hfsq, r)), k_lo)), f));
  const __m256d other_log = _mm256_sub_pd(
      k_hi, _mm256_sub_pd(_mm256_sub_pd(_mm256_mul_pd(s, _mm256_sub_pd(f, r)), k_lo), f));
  const __m256d tiny = _mm256_castsi256_pd(_mm256_cmpgt_epi64(
      integer(3), _mm256_and_si256(_mm256_add_epi64(high, integer(2)), integer(0x000fffff))));
  const __m256d middle =
      _mm256_castsi256_pd(_mm256_and_si256(_mm256_cmpgt_epi64(high, integer(0x6147a - 1)),
                                           _mm256_cmpgt_epi64(integer(0x6b851 + 1), high)));
  return _mm256_blendv_pd(_mm256_blendv_pd(other_log, middle_log, middle), tiny_log, tiny);
}

// The polar method's factor sqrt(-2 log(s) / s), in RandomStream::normal's operations.
__m256d polar_factor(__m256d s) {
  const __m256d log_s = polar_log4(s);
  return _mm256_sqrt_pd(_mm256_div_pd(_mm256_mul_pd(_mm256_set1_pd(-2.0), log_s), s));
}

}  // namespace

bool normal_triples_vectorised() {
  return true;
}

// The AVX-512 form four streams at a time, its masks as lanes of all ones; the third block
// made only for the vectors with a lane that has not accepted two of its first four pairs
// (one vector in eight: a pair is accepted with probability pi/4, so a stream lacks two in
// four with probability 0.033), the same numbers as made for every vector (its samples 0.90x
// in the default input's Langevin start, bench/README.md, stop 52).
constexpr int kBlocks = 3;

void normal_triples(std::uint64_t seed, const PhiloxCounter* start, std::size_t count, Vec3* out) {
  const auto key0 = static_cast<std::uint32_t>(seed), key1 = static_cast<std::uint32_t>(seed >> 32);
  const __m256d one = _mm256_set1_pd(1.0);
  std::size_t k = 0;
  for (; k + 4 <= count; k += 4) {
    // The four counters' words transposed in registers, each zero-extended to its 64-bit lane.
    // (Through a stack array, by 8-byte stores, each vector's 32-byte load waited for the
    // stores to drain: its stores are not forwarded to it, 11 % of this function's samples.)
    __m128i rows[4];
    for (int l = 0; l < 4; ++l) {
      rows[l] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(start[k + l].data()));
    }
    const __m128i low01 = _mm_unpacklo_epi32(rows[0], rows[1]);   // 0.0 1.0 0.1 1.1
    const __m128i low23 = _mm_unpacklo_epi32(rows[2], rows[3]);   // 2.0 3.0 2.1 3.1
    const __m128i high01 = _mm_unpackhi_epi32(rows[0], rows[1]);  // 0.2 1.2 0.3 1.3
    const __m128i high23 = _mm_unpackhi_epi32(rows[2], rows[3]);
    Block4 counter;
    counter.w[0] = _mm256_cvtepu32_epi64(_mm_unpacklo_epi64(low01, low23));
    counter.w[1] = _mm256_cvtepu32_epi64(_mm_unpackhi_epi64(low01, low23));
    counter.w[2] = _mm256_cvtepu32_epi64(_mm_unpacklo_epi64(high01, high23));
    counter.w[3] = _mm256_cvtepu32_epi64(_mm_unpackhi_epi64(high01, high23));
    // The stream's blocks: the counter's last word plus 0, 1 and 2 (RandomStream::refill),
    // in 32 bits.
    Block4 block[kBlocks];
    auto make_block = [&](int b) {
      block[b] = philox4(counter, key0, key1);
      counter.w[3] = _mm256_and_si256(_mm256_add_epi64(counter.w[3], _mm256_set1_epi64x(1)),
                                      _mm256_set1_epi64x(0xffffffffLL));
    };
    // The first accepted pair (u1, v1, s1), then the next accepted one after it (u2, s2);
    // lanes with fewer than two accepted among the first six pairs are drawn by RandomStream
    // (s = 1 until a pair is found: such a lane takes no logarithm of 0).
    __m256d u1 = _mm256_setzero_pd(), v1 = u1, u2 = u1, s1 = one, s2 = one;
    __m256d none_before = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    __m256d one_before = _mm256_setzero_pd(), second_found = _mm256_setzero_pd();
    auto take_pairs = [&](int first_pair, int last_pair) {
      constexpr int pairs = 2 * kBlocks;
      __m256d u[pairs], v[pairs], s[pairs], accepted[pairs];
      for (int q = first_pair; q < last_pair; ++q) {
        const Block4& b = block[q / 2];
        u[q] = symmetric(b.w[2 * (q % 2)]);
        v[q] = symmetric(b.w[2 * (q % 2) + 1]);
        s[q] = _mm256_add_pd(_mm256_mul_pd(u[q], u[q]), _mm256_mul_pd(v[q], v[q]));
        accepted[q] = _mm256_cmp_pd(s[q], one, _CMP_LT_OQ);
      }
      for (int q = first_pair; q < last_pair; ++q) {
        const __m256d first_here = _mm256_and_pd(none_before, accepted[q]);
        const __m256d second_here = _mm256_and_pd(one_before, accepted[q]);
        u1 = _mm256_blendv_pd(u1, u[q], first_here);
        v1 = _mm256_blendv_pd(v1, v[q], first_here);
        s1 = _mm256_blendv_pd(s1, s[q], first_here);
        u2 = _mm256_blendv_pd(u2, u[q], second_here);
        s2 = _mm256_blendv_pd(s2, s[q], second_here);
        second_found = _mm256_or_pd(second_found, second_here);
        one_before = _mm256_or_pd(_mm256_andnot_pd(accepted[q], one_before), first_here);
        none_before = _mm256_andnot_pd(accepted[q], none_before);
      }
    };
    make_block(0);
    make_block(1);
    take_pairs(0, 4);
    if (_mm256_movemask_pd(second_found) != 0xf) {
      make_block(2);
      take_pairs(4, 6);
    }
    const __m256d f1 = polar_factor(s1), f2 = polar_factor(s2);
    alignas(32) double x[4], y[4], z[4];
    _mm256_store_pd(x, _mm256_mul_pd(u1, f1));
    _mm256_store_pd(y, _mm256_mul_pd(v1, f1));
    _mm256_store_pd(z, _mm256_mul_pd(u2, f2));
    const auto found = static_cast<unsigned>(_mm256_movemask_pd(second_found));
    for (int l = 0; l < 4; ++l) {
      if (found >> l & 1) {
        out[k + l] = {x[l], y[l], z[l]};
      } else {
        normal_triples_by_stream(seed, start + k + l, 1, out + k + l);
      }
    }
  }
  normal_triples_by_stream(seed, start + k, count - k, out + k);
}
#else
bool normal_triples_vectorised() {
  return false;
}

void normal_triples(std::uint64_t seed, const PhiloxCounter* start, std::size_t count, Vec3* out) {
  normal_triples_by_stream(seed, start, count, out);
}
#endif

}  // namespace deli
