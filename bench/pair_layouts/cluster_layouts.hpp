#pragma once

// Two cluster layouts of a half list's pairs, for measuring them against the list itself
// (pair_layouts.cpp). A cluster is four consecutive items (slots or particles) 4I..4I+3.
// - Quads (4x1): per cluster, entries (partner j, image code, four lane bits: which of the
//   cluster's items list j with that code). A vector holds the four items against one j.
// - Cluster pairs (4x4): per cluster I, entries (cluster J, image code, sixteen bits: bit
//   4a + b when item 4I+a lists 4J+b with that code). A vector holds one item of I against
//   the four of J; rows without a pair are skipped.
// Both are made from the list in its order and hold exactly its pairs. Each kernel has a
// scalar form with its operations in its order (the same bits), for checking.

#include <cstdint>
#include <vector>

#include "neighbor/neighbor_list.hpp"
#include "pair/lennard_jones.hpp"
#include "pair/vector_pair_loop.hpp"

#ifdef __AVX2__
#include <immintrin.h>
#endif

namespace deli::bench {

struct ClusterEntries {
  std::vector<std::size_t> offsets;   // per cluster: its entries [offsets[I], offsets[I + 1])
  std::vector<std::int32_t> partner;  // quads: a partner item; cluster pairs: a cluster
  std::vector<std::uint8_t> code;
  std::vector<std::uint16_t> bits;
};

// `partner_of(j)`: j itself (quads) or j / 4 (cluster pairs); `bit_of(a, j)` the entry's bit
// for item a of the cluster and partner item j.
template <class PartnerOf, class BitOf>
void group_by_cluster(const NeighborList::PartnerRanges& r, std::size_t items, std::size_t partners,
                      PartnerOf partner_of, BitOf bit_of, ClusterEntries& out,
                      std::vector<std::int32_t>& stamp, std::vector<std::int32_t>& entry_of) {
  const std::size_t clusters = (items + 3) / 4;
  out.offsets.assign(1, 0);
  out.partner.clear(), out.code.clear(), out.bits.clear();
  stamp.assign(partners, -1);
  entry_of.resize(partners);
  for (std::size_t c = 0; c < clusters; ++c) {
    const auto cluster = static_cast<std::int32_t>(c);
    for (std::size_t a = 0; a < 4 && 4 * c + a < items; ++a) {
      const std::size_t i = 4 * c + a;
      for (std::size_t k = r.begin[i]; k < r.end[i]; ++k) {
        const std::int32_t j = r.neighbors[k];
        const std::int32_t p = partner_of(j);
        const std::uint8_t code = r.image_codes[k];
        const auto bit = static_cast<std::uint16_t>(bit_of(a, j));
        const auto e = static_cast<std::size_t>(entry_of[static_cast<std::size_t>(p)]);
        if (stamp[static_cast<std::size_t>(p)] == cluster && out.code[e] == code) {
          out.bits[e] = static_cast<std::uint16_t>(out.bits[e] | bit);
        } else {
          stamp[static_cast<std::size_t>(p)] = cluster;
          entry_of[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(out.partner.size());
          out.partner.push_back(p), out.code.push_back(code), out.bits.push_back(bit);
        }
      }
    }
    out.offsets.push_back(out.partner.size());
  }
}

inline void make_quads(const NeighborList::PartnerRanges& r, std::size_t items, ClusterEntries& out,
                       std::vector<std::int32_t>& stamp, std::vector<std::int32_t>& entry_of) {
  group_by_cluster(
      r, items, items, [](std::int32_t j) { return j; },
      [](std::size_t a, std::int32_t) { return 1u << a; }, out, stamp, entry_of);
}

inline void make_cluster_pairs(const NeighborList::PartnerRanges& r, std::size_t items,
                               ClusterEntries& out, std::vector<std::int32_t>& stamp,
                               std::vector<std::int32_t>& entry_of) {
  group_by_cluster(
      r, items, (items + 3) / 4, [](std::int32_t j) { return j >> 2; },
      [](std::size_t a, std::int32_t j) { return 1u << (4 * a + static_cast<std::size_t>(j & 3)); },
      out, stamp, entry_of);
}

// Positions and forces by item, padded to a multiple of four items.
struct ClusterChunk {
  const PaddedVec3* x;
  PaddedVec3* f;
  const ClusterEntries* entries;
  const Vec3* shifts;
  std::size_t first, last;  // clusters
};

// The four lanes' sum in the kernels' order: (0 + 1) + (2 + 3).
inline double lane_sum(const double (&v)[4]) {
  return (v[0] + v[1]) + (v[2] + v[3]);
}

// The pair's force over r, +0 outside the cutoff or without its bit.
inline void pair_force(const LennardJones::Params& p, bool listed, double dx, double dy, double dz,
                       double& fx, double& fy, double& fz) {
  const double r2 = dx * dx + dy * dy + dz * dz;
  fx = fy = fz = 0.0;
  if (listed && r2 < p.cutoff2) {
    double f_over_r, e;
    LennardJones::evaluate(p, r2, f_over_r, e);
    fx = dx * f_over_r, fy = dy * f_over_r, fz = dz * f_over_r;
  }
}

// Quads one pair at a time: separations (x_i - x_j) - shift; each item's force summed by
// entry, each partner's as lane_sum of the entry's four.
inline void quads_scalar(const LennardJones::Params& p, const ClusterChunk& c) {
  const ClusterEntries& q = *c.entries;
  for (std::size_t I = c.first; I < c.last; ++I) {
    const PaddedVec3* xi = c.x + 4 * I;
    double ax[4] = {}, ay[4] = {}, az[4] = {};
    for (std::size_t e = q.offsets[I]; e < q.offsets[I + 1]; ++e) {
      const PaddedVec3& xj = c.x[q.partner[e]];
      const Vec3& s = c.shifts[q.code[e]];
      double fx[4], fy[4], fz[4];
      for (int a = 0; a < 4; ++a) {
        pair_force(p, q.bits[e] >> a & 1, (xi[a].x - xj.x) - s.x, (xi[a].y - xj.y) - s.y,
                   (xi[a].z - xj.z) - s.z, fx[a], fy[a], fz[a]);
        ax[a] += fx[a], ay[a] += fy[a], az[a] += fz[a];
      }
      PaddedVec3& fj = c.f[q.partner[e]];
      fj.x -= lane_sum(fx), fj.y -= lane_sum(fy), fj.z -= lane_sum(fz);
    }
    for (int a = 0; a < 4; ++a)
      c.f[4 * I + a].x += ax[a], c.f[4 * I + a].y += ay[a], c.f[4 * I + a].z += az[a];
  }
}

// Cluster pairs one pair at a time: separations x_i - (x_j + shift); item a's force summed
// by lane (J's item b) then lane_sum, J's items' by row.
inline void cluster_pairs_scalar(const LennardJones::Params& p, const ClusterChunk& c) {
  const ClusterEntries& q = *c.entries;
  for (std::size_t I = c.first; I < c.last; ++I) {
    const PaddedVec3* xi = c.x + 4 * I;
    double fi[4][3][4] = {};
    for (std::size_t e = q.offsets[I]; e < q.offsets[I + 1]; ++e) {
      PaddedVec3* fj = c.f + 4 * static_cast<std::size_t>(q.partner[e]);
      const PaddedVec3* xj = c.x + 4 * static_cast<std::size_t>(q.partner[e]);
      const Vec3& s = c.shifts[q.code[e]];
      double sum[3][4] = {};
      for (int a = 0; a < 4; ++a) {
        if ((q.bits[e] >> (4 * a) & 15u) == 0) continue;
        for (int b = 0; b < 4; ++b) {
          double fx, fy, fz;
          pair_force(p, q.bits[e] >> (4 * a + b) & 1, xi[a].x - (xj[b].x + s.x),
                     xi[a].y - (xj[b].y + s.y), xi[a].z - (xj[b].z + s.z), fx, fy, fz);
          fi[a][0][b] += fx, fi[a][1][b] += fy, fi[a][2][b] += fz;
          sum[0][b] += fx, sum[1][b] += fy, sum[2][b] += fz;
        }
      }
      for (int b = 0; b < 4; ++b) fj[b].x -= sum[0][b], fj[b].y -= sum[1][b], fj[b].z -= sum[2][b];
    }
    for (int a = 0; a < 4; ++a) {
      c.f[4 * I + a].x += lane_sum(fi[a][0]);
      c.f[4 * I + a].y += lane_sum(fi[a][1]);
      c.f[4 * I + a].z += lane_sum(fi[a][2]);
    }
  }
}

#ifdef __AVX2__
struct KernelTables {
  alignas(32) PaddedVec3 shift[32] = {};
  alignas(32) std::int64_t lanes[16][4] = {};
  explicit KernelTables(const Vec3* shifts) {
    for (int code = 0; code < 27; ++code)
      shift[code] = {shifts[code].x, shifts[code].y, shifts[code].z, 0.0};
    for (int m = 0; m < 16; ++m)
      for (int l = 0; l < 4; ++l) lanes[m][l] = (m >> l & 1) ? -1 : 0;
  }
  __m256d lane_mask(unsigned m) const {
    return _mm256_load_pd(reinterpret_cast<const double*>(lanes[m]));
  }
};

// f/r by lane for r^2 inside `in` (+0 elsewhere), as LennardJones::evaluate.
inline __m256d force_over_r(const LennardJones::Params& p, __m256d r2, __m256d in) {
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d r2inv = _mm256_div_pd(one, _mm256_blendv_pd(one, r2, in));
  const __m256d r6inv = _mm256_mul_pd(_mm256_mul_pd(r2inv, r2inv), r2inv);
  return _mm256_mul_pd(
      _mm256_mul_pd(
          r6inv, _mm256_sub_pd(_mm256_mul_pd(_mm256_set1_pd(p.lj1), r6inv), _mm256_set1_pd(p.lj2))),
      r2inv);
}

inline __m256d squared(__m256d dx, __m256d dy, __m256d dz) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                       _mm256_mul_pd(dz, dz));
}

// Four padded items as x, y and z vectors.
inline void load_transposed(const PaddedVec3* v, __m256d& x, __m256d& y, __m256d& z) {
  const __m256d p0 = _mm256_load_pd(&v[0].x), p1 = _mm256_load_pd(&v[1].x);
  const __m256d p2 = _mm256_load_pd(&v[2].x), p3 = _mm256_load_pd(&v[3].x);
  const __m256d t0 = _mm256_unpacklo_pd(p0, p1), t1 = _mm256_unpackhi_pd(p0, p1);
  const __m256d t2 = _mm256_unpacklo_pd(p2, p3), t3 = _mm256_unpackhi_pd(p2, p3);
  x = _mm256_permute2f128_pd(t0, t2, 0x20);
  y = _mm256_permute2f128_pd(t1, t3, 0x20);
  z = _mm256_permute2f128_pd(t0, t2, 0x31);
}

// v[b] op= (x, y, z)[b] for the four lanes b, op add or subtract.
template <bool kAdd>
inline void update_transposed(PaddedVec3* v, __m256d x, __m256d y, __m256d z) {
  const __m256d zero = _mm256_setzero_pd();
  const __m256d xy02 = _mm256_unpacklo_pd(x, y), xy13 = _mm256_unpackhi_pd(x, y);
  const __m256d z02 = _mm256_unpacklo_pd(z, zero), z13 = _mm256_unpackhi_pd(z, zero);
  const __m256d lane[4] = {
      _mm256_permute2f128_pd(xy02, z02, 0x20), _mm256_permute2f128_pd(xy13, z13, 0x20),
      _mm256_permute2f128_pd(xy02, z02, 0x31), _mm256_permute2f128_pd(xy13, z13, 0x31)};
  for (int b = 0; b < 4; ++b) {
    double* q = &v[b].x;
    const __m256d old = _mm256_load_pd(q);
    _mm256_store_pd(q, kAdd ? _mm256_add_pd(old, lane[b]) : _mm256_sub_pd(old, lane[b]));
  }
}

inline void quads_avx2(const LennardJones::Params& p, const ClusterChunk& c) {
  const KernelTables t(c.shifts);
  const __m256d cutoff2 = _mm256_set1_pd(p.cutoff2);
  const ClusterEntries& q = *c.entries;
  for (std::size_t I = c.first; I < c.last; ++I) {
    __m256d xi, yi, zi;
    load_transposed(c.x + 4 * I, xi, yi, zi);
    __m256d fxi = _mm256_setzero_pd(), fyi = fxi, fzi = fxi;
    for (std::size_t e = q.offsets[I]; e < q.offsets[I + 1]; ++e) {
      const double* xj = &c.x[q.partner[e]].x;
      const double* s = &t.shift[q.code[e]].x;
      const __m256d dx =
          _mm256_sub_pd(_mm256_sub_pd(xi, _mm256_broadcast_sd(xj)), _mm256_broadcast_sd(s));
      const __m256d dy =
          _mm256_sub_pd(_mm256_sub_pd(yi, _mm256_broadcast_sd(xj + 1)), _mm256_broadcast_sd(s + 1));
      const __m256d dz =
          _mm256_sub_pd(_mm256_sub_pd(zi, _mm256_broadcast_sd(xj + 2)), _mm256_broadcast_sd(s + 2));
      const __m256d r2 = squared(dx, dy, dz);
      const __m256d in =
          _mm256_and_pd(t.lane_mask(q.bits[e]), _mm256_cmp_pd(r2, cutoff2, _CMP_LT_OQ));
      const __m256d f_over_r = force_over_r(p, r2, in);
      const __m256d fx = _mm256_and_pd(in, _mm256_mul_pd(dx, f_over_r));
      const __m256d fy = _mm256_and_pd(in, _mm256_mul_pd(dy, f_over_r));
      const __m256d fz = _mm256_and_pd(in, _mm256_mul_pd(dz, f_over_r));
      fxi = _mm256_add_pd(fxi, fx), fyi = _mm256_add_pd(fyi, fy), fzi = _mm256_add_pd(fzi, fz);
      // The partner's (sum x, sum y, sum z, 0), each as lane_sum.
      const __m256d h0 = _mm256_hadd_pd(fx, fy), h1 = _mm256_hadd_pd(fz, _mm256_setzero_pd());
      const __m256d sum =
          _mm256_add_pd(_mm256_permute2f128_pd(h0, h1, 0x20), _mm256_permute2f128_pd(h0, h1, 0x31));
      double* fj = &c.f[q.partner[e]].x;
      _mm256_store_pd(fj, _mm256_sub_pd(_mm256_load_pd(fj), sum));
    }
    update_transposed<true>(c.f + 4 * I, fxi, fyi, fzi);
  }
}

inline void cluster_pairs_avx2(const LennardJones::Params& p, const ClusterChunk& c) {
  const KernelTables t(c.shifts);
  const __m256d cutoff2 = _mm256_set1_pd(p.cutoff2);
  const ClusterEntries& q = *c.entries;
  for (std::size_t I = c.first; I < c.last; ++I) {
    const PaddedVec3* xi = c.x + 4 * I;
    __m256d fi[4][3];
    for (auto& row : fi) row[0] = row[1] = row[2] = _mm256_setzero_pd();
    for (std::size_t e = q.offsets[I]; e < q.offsets[I + 1]; ++e) {
      const std::size_t J = 4 * static_cast<std::size_t>(q.partner[e]);
      __m256d xj, yj, zj;
      load_transposed(c.x + J, xj, yj, zj);
      const double* s = &t.shift[q.code[e]].x;
      xj = _mm256_add_pd(xj, _mm256_broadcast_sd(s));
      yj = _mm256_add_pd(yj, _mm256_broadcast_sd(s + 1));
      zj = _mm256_add_pd(zj, _mm256_broadcast_sd(s + 2));
      __m256d fjx = _mm256_setzero_pd(), fjy = fjx, fjz = fjx;
      const unsigned bits = q.bits[e];
#pragma GCC unroll 4
      for (int a = 0; a < 4; ++a) {
        const unsigned row = bits >> (4 * a) & 15u;
        if (row == 0) continue;
        const __m256d dx = _mm256_sub_pd(_mm256_broadcast_sd(&xi[a].x), xj);
        const __m256d dy = _mm256_sub_pd(_mm256_broadcast_sd(&xi[a].y), yj);
        const __m256d dz = _mm256_sub_pd(_mm256_broadcast_sd(&xi[a].z), zj);
        const __m256d r2 = squared(dx, dy, dz);
        const __m256d in = _mm256_and_pd(t.lane_mask(row), _mm256_cmp_pd(r2, cutoff2, _CMP_LT_OQ));
        const __m256d f_over_r = force_over_r(p, r2, in);
        const __m256d fx = _mm256_and_pd(in, _mm256_mul_pd(dx, f_over_r));
        const __m256d fy = _mm256_and_pd(in, _mm256_mul_pd(dy, f_over_r));
        const __m256d fz = _mm256_and_pd(in, _mm256_mul_pd(dz, f_over_r));
        fi[a][0] = _mm256_add_pd(fi[a][0], fx);
        fi[a][1] = _mm256_add_pd(fi[a][1], fy);
        fi[a][2] = _mm256_add_pd(fi[a][2], fz);
        fjx = _mm256_add_pd(fjx, fx), fjy = _mm256_add_pd(fjy, fy), fjz = _mm256_add_pd(fjz, fz);
      }
      update_transposed<false>(c.f + J, fjx, fjy, fjz);
    }
    // Item a's sums: the four rows' lanes added as lane_sum, by a transpose-free hadd.
    for (int a = 0; a < 4; ++a) {
      const __m256d h0 = _mm256_hadd_pd(fi[a][0], fi[a][1]);
      const __m256d h1 = _mm256_hadd_pd(fi[a][2], _mm256_setzero_pd());
      const __m256d sum =
          _mm256_add_pd(_mm256_permute2f128_pd(h0, h1, 0x20), _mm256_permute2f128_pd(h0, h1, 0x31));
      double* q4 = &c.f[4 * I + static_cast<std::size_t>(a)].x;
      _mm256_store_pd(q4, _mm256_add_pd(_mm256_load_pd(q4), sum));
    }
  }
}
#endif

}  // namespace deli::bench
