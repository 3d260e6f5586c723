#include "solvers/rod_chain_passes.hpp"

#include "core/lane_vectors.hpp"

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace deli::rod_passes {

// __restrict: the arrays never overlap, so the loops vectorise without runtime alias checks.
// Builtins instead of std::sqrt and std::abs: no inline library code shared with files
// built for another CPU.

namespace {
constexpr double bound_slack = 0x1p-50;

// One rod's held_bounds entry (bound and usability) from its squared length d2.
inline void held_bound_of(double d2, double l, double inverse_l, double tolerance, double& bound,
                          std::uint8_t& usable) {
  const double relative_gap = __builtin_fabs(d2 - l * l) * inverse_l;
  const double rod_bound = relative_gap * (1 + bound_slack) + l * bound_slack;
  bound = rod_bound;
  // Also false for NaN.
  usable = static_cast<std::uint8_t>((relative_gap <= 0.25 * l) & (rod_bound <= tolerance));
}

// differences() with a pointer per axis (restrict: no runtime overlap checks); with
// `bounds`, held_bounds() of the squared lengths in the same pass.
template <bool bounds>
inline bool differences_by_axis(std::size_t m, const double* __restrict bx,
                                const double* __restrict by, const double* __restrict bz,
                                const double* __restrict forward, const double* __restrict ix,
                                const double* __restrict iy, const double* __restrict iz,
                                const double* __restrict period, const double* __restrict limit,
                                double* __restrict dx, double* __restrict dy, double* __restrict dz,
                                double* __restrict d2, const double* __restrict length,
                                const double* __restrict inverse_length, double tolerance,
                                double* __restrict bound, std::uint8_t* __restrict usable) {
  const double px = period[0], py = period[1], pz = period[2];
  const double lx = limit[0], ly = limit[1], lz = limit[2];
  int hold = 1;
  for (std::size_t k = 0; k < m; ++k) {
    const bool f = forward[k] > 0;
    const double ax = bx[k], ay = by[k], az = bz[k];
    const double cx = bx[k + 1], cy = by[k + 1], cz = bz[k + 1];
    double ex = (f ? ax : cx) - (f ? cx : ax);
    double ey = (f ? ay : cy) - (f ? cy : ay);
    double ez = (f ? az : cz) - (f ? cz : az);
    ex -= px * ix[k];
    ey -= py * iy[k];
    ez -= pz * iz[k];
    // Also false for NaN.
    hold &= static_cast<int>(__builtin_fabs(ex) <= lx) &
            static_cast<int>(__builtin_fabs(ey) <= ly) & static_cast<int>(__builtin_fabs(ez) <= lz);
    dx[k] = ex;
    dy[k] = ey;
    dz[k] = ez;
    const double squared = ex * ex + ey * ey + ez * ez;
    d2[k] = squared;
    if constexpr (bounds) {
      held_bound_of(squared, length[k], inverse_length[k], tolerance, bound[k], usable[k]);
    }
  }
  return hold != 0;
}
}  // namespace

bool differences(std::size_t m, const double* x, const double* forward, const double* image,
                 const double* period, const double* limit, double* d, double* d2) {
  const std::size_t n = m + 1;
  return differences_by_axis<false>(m, x, x + n, x + 2 * n, forward, image, image + m,
                                    image + 2 * m, period, limit, d, d + m, d + 2 * m, d2, nullptr,
                                    nullptr, 0.0, nullptr, nullptr);
}

bool differences_and_bounds(std::size_t m, const double* x, const double* forward,
                            const double* image, const double* period, const double* limit,
                            const double* length, const double* inverse_length, double tolerance,
                            double* d, double* d2, double* bound, std::uint8_t* usable) {
  const std::size_t n = m + 1;
  return differences_by_axis<true>(m, x, x + n, x + 2 * n, forward, image, image + m, image + 2 * m,
                                   period, limit, d, d + m, d + 2 * m, d2, length, inverse_length,
                                   tolerance, bound, usable);
}

namespace {
// Row k of m rows by axis: its length from its squared length r[k] (kept in r[k]) and its
// direction d scaled to unit length (zero for a zero-length row); returns the length.
inline double normalize_row(std::size_t m, std::size_t k, double* __restrict d,
                            double* __restrict r) {
  const double length = __builtin_sqrt(r[k]);
  const double inverse = 1.0 / length;
  const bool positive = length > 0;
  r[k] = length;
  d[k] = positive ? d[k] * inverse : 0.0;
  d[m + k] = positive ? d[m + k] * inverse : 0.0;
  d[2 * m + k] = positive ? d[2 * m + k] * inverse : 0.0;
  return length;
}
}  // namespace

void normalize(std::size_t m, double* __restrict d, double* __restrict r) {
  for (std::size_t k = 0; k < m; ++k) normalize_row(m, k, d, r);
}

double normalize_residual(std::size_t m, double* __restrict d, double* __restrict r,
                          const double* __restrict length, double* __restrict phi) {
  for (std::size_t k = 0; k < m; ++k) phi[k] = normalize_row(m, k, d, r) - length[k];
  // residual_norm: the largest |phi_k| (a maximum, the same in any order), +inf unless every
  // phi_k is finite.
  double largest = 0.0;
  bool finite = true;
  for (std::size_t k = 0; k < m; ++k) {
    const double a = __builtin_fabs(phi[k]);
    finite &= (phi[k] - phi[k]) == 0;
    largest = a > largest ? a : largest;
  }
  return finite ? largest : __builtin_inf();
}

void held_bounds(std::size_t m, const double* __restrict d2, const double* __restrict length,
                 const double* __restrict inverse_length, double tolerance,
                 double* __restrict bound, std::uint8_t* __restrict usable) {
  for (std::size_t k = 0; k < m; ++k) {
    held_bound_of(d2[k], length[k], inverse_length[k], tolerance, bound[k], usable[k]);
  }
}

namespace {
// One bead's impulse component from its rods a = b - 1 and b (the ends have one rod).
inline void impulse_components(std::size_t m, const double* __restrict u,
                               const double* __restrict z, const double* __restrict first_sign,
                               const double* __restrict second_sign, double* __restrict ix,
                               double* __restrict iy, double* __restrict iz) {
  const std::size_t n = m + 1;
  const double* __restrict ux = u;
  const double* __restrict uy = u + m;
  const double* __restrict uz = u + 2 * m;
  {
    const double s = first_sign[0] * z[0];
    ix[0] = 0.0 + ux[0] * s;
    iy[0] = 0.0 + uy[0] * s;
    iz[0] = 0.0 + uz[0] * s;
  }
  for (std::size_t b = 1; b + 1 < n; ++b) {
    const double sa = first_sign[b] * z[b - 1];
    const double sb = second_sign[b] * z[b];
    ix[b] = (0.0 + ux[b - 1] * sa) + ux[b] * sb;
    iy[b] = (0.0 + uy[b - 1] * sa) + uy[b] * sb;
    iz[b] = (0.0 + uz[b - 1] * sa) + uz[b] * sb;
  }
  {
    const std::size_t b = n - 1;
    const double s = first_sign[b] * z[b - 1];
    ix[b] = 0.0 + ux[b - 1] * s;
    iy[b] = 0.0 + uy[b - 1] * s;
    iz[b] = 0.0 + uz[b - 1] * s;
  }
}
}  // namespace

void impulses(std::size_t m, const double* u, const double* z, const double* first_sign,
              const double* second_sign, double* out) {
  const std::size_t n = m + 1;
  impulse_components(m, u, z, first_sign, second_sign, out, out + n, out + 2 * n);
}

void positions(std::size_t m, const double* __restrict x0, const double* __restrict u,
               const double* __restrict z, const double* __restrict first_sign,
               const double* __restrict second_sign, const double* __restrict hw,
               double* __restrict out) {
  // impulse_components' sums, each added to x0 as it is made (one pass per axis).
  const std::size_t n = m + 1;
  for (std::size_t c = 0; c < 3; ++c) {
    const double* __restrict uc = u + c * m;
    const double* __restrict x0c = x0 + c * n;
    double* __restrict oc = out + c * n;
    oc[0] = x0c[0] + (0.0 + uc[0] * (first_sign[0] * z[0])) * hw[0];
    for (std::size_t b = 1; b + 1 < n; ++b) {
      const double sa = first_sign[b] * z[b - 1];
      const double sb = second_sign[b] * z[b];
      oc[b] = x0c[b] + ((0.0 + uc[b - 1] * sa) + uc[b] * sb) * hw[b];
    }
    const std::size_t b = n - 1;
    oc[b] = x0c[b] + (0.0 + uc[b - 1] * (first_sign[b] * z[b - 1])) * hw[b];
  }
}

void bands(std::size_t m, const double* __restrict a, const double* __restrict b,
           const double* __restrict w_low, const double* __restrict w_high,
           const double* __restrict coupling, double scale, const double* __restrict minus_rhs,
           double* __restrict lower, double* __restrict diagonal, double* __restrict upper,
           double* __restrict rhs) {
  const double* __restrict ax = a;
  const double* __restrict ay = a + m;
  const double* __restrict az = a + 2 * m;
  const double* __restrict bx = b;
  const double* __restrict by = b + m;
  const double* __restrict bz = b + 2 * m;
  for (std::size_t k = 0; k < m; ++k) {
    const double d = ax[k] * bx[k] + ay[k] * by[k] + az[k] * bz[k];
    double entry = 0.0;
    entry += 1.0 * w_low[k] * d;
    entry += 1.0 * w_high[k] * d;
    diagonal[k] = entry * scale;
    rhs[k] = -minus_rhs[k];
  }
  for (std::size_t k = 0; k + 1 < m; ++k) {
    const double up = ax[k] * bx[k + 1] + ay[k] * by[k + 1] + az[k] * bz[k + 1];
    upper[k] = (0.0 + coupling[k] * up) * scale;
    const double down = ax[k + 1] * bx[k] + ay[k + 1] * by[k] + az[k + 1] * bz[k];
    lower[k + 1] = (0.0 + coupling[k] * down) * scale;
  }
}

void projections(std::size_t m, const double* __restrict u, const double* __restrict v,
                 const double* __restrict low_first, const double* __restrict low_sign,
                 const double* __restrict high_sign, double* __restrict out) {
  const std::size_t n = m + 1;
  const double* __restrict vx = v;
  const double* __restrict vy = v + n;
  const double* __restrict vz = v + 2 * n;
  for (std::size_t k = 0; k < m; ++k) {
    const bool f = low_first[k] > 0;
    const double ax = vx[k], ay = vy[k], az = vz[k];
    const double cx = vx[k + 1], cy = vy[k + 1], cz = vz[k + 1];
    const double ux = u[k], uy = u[m + k], uz = u[2 * m + k];
    const double to_low = ux * (f ? ax : cx) + uy * (f ? ay : cy) + uz * (f ? az : cz);
    const double to_high = ux * (f ? cx : ax) + uy * (f ? cy : ay) + uz * (f ? cz : az);
    double projected = 0.0;
    projected += low_sign[k] * to_low;
    projected += high_sign[k] * to_high;
    out[k] = projected;
  }
}

namespace {
// One entry per lane (core/lane_vectors.hpp).
static_assert(lane_vectors::width == lanes);
using namespace lane_vectors;  // Lanes, LaneMask, load, store, broadcast, shuffle

// The lanes' bit patterns (compared as integers: -0 and +0 differ, a NaN equals itself).
template <class V>
inline auto bits(const V& v) {
  decltype(v < v) b;
  __builtin_memcpy(&b, &v, sizeof b);
  return b;
}
// |v| but for the sign of a zero (only compared here); NaN stays NaN.
template <class V>
inline V magnitude(const V& v) {
  return v < 0 ? -v : v;
}
// A pivot lost to cancellation (relative to its diagonal entry) means dependent rows: all
// ones where it is not.
template <class V>
inline auto keeps(const V& pivot, const V& diagonal_entry) {
  return magnitude(pivot) > 1e-12 * magnitude(diagonal_entry);
}
// All ones where v is finite (v - v is 0 exactly then, NaN otherwise).
template <class V>
inline auto finite(const V& v) {
  return (v - v) == 0;
}
// pass(V{}, half) for the lanes half.. of a vector type V: the eight lanes in two halves of
// four where the CPU has AVX2 and not AVX-512, else at once. As eight (two registers each),
// a pass's live vectors did not fit AVX2's sixteen registers and up to half its instructions
// were spills. Each lane's operations are the same either way.
template <class Pass>
inline void in_lane_vectors(Pass&& pass) {
  if constexpr (kQuarterLanes) {
    pass(Quarter{}, 0);
    pass(Quarter{}, 4);
  } else {
    pass(Lanes{}, 0);
  }
}
}  // namespace

namespace {
// eliminate_lanes of the rows' entries as `rows` gives them (diagonal(k), rhs(k), lower(k) for
// k > 0, upper(k) for k < n - 1), each asked for where the elimination first reads it.
template <class V, class Rows>
inline void eliminate_rows(std::size_t n, const Rows& rows, std::size_t half, double* __restrict x,
                           double* __restrict c, std::uint8_t* __restrict solved) {
  constexpr std::size_t w = lanes;
  using M = decltype(V{} < V{});
  auto load = [half](const double* p) { return load_as<V>(p + half); };
  auto store = [half](double* p, const V& v) { store_as<V>(p + half, v); };
  if (n == 0) {
    for (std::size_t l = 0; l < lanes_in<V>; ++l) solved[half + l] = 1;
    return;
  }
  M regular = {};
  regular = regular == 0;  // all ones
  const std::size_t meet = n / 2;
  const std::size_t below = n - 1 - meet;
  for (std::size_t step = 0; step < meet; ++step) {
    {
      const std::size_t k = step;
      const V d = rows.diagonal(k);
      V pivot = d, y = rows.rhs(k);
      if (k > 0) {
        const V lo = rows.lower(k);
        pivot = d - lo * load(c + (k - 1) * w);
        y -= lo * load(x + (k - 1) * w);
      }
      regular &= keeps(pivot, d);
      const V reciprocal = 1.0 / pivot;
      store(c + k * w, rows.upper(k) * reciprocal);
      store(x + k * w, y * reciprocal);
    }
    if (step < below) {
      const std::size_t k = n - 1 - step;
      const V d = rows.diagonal(k);
      V pivot = d, y = rows.rhs(k);
      if (k < n - 1) {
        const V up = rows.upper(k);
        pivot = d - up * load(c + (k + 1) * w);
        y -= up * load(x + (k + 1) * w);
      }
      regular &= keeps(pivot, d);
      const V reciprocal = 1.0 / pivot;
      store(c + k * w, rows.lower(k) * reciprocal);
      store(x + k * w, y * reciprocal);
    }
  }
  M all_finite;
  {
    const std::size_t k = meet;
    const V d = rows.diagonal(k);
    V pivot = d, y = rows.rhs(k);
    if (k > 0) {
      const V lo = rows.lower(k);
      pivot -= lo * load(c + (k - 1) * w);
      y -= lo * load(x + (k - 1) * w);
    }
    if (k < n - 1) {
      const V up = rows.upper(k);
      pivot -= up * load(c + (k + 1) * w);
      y -= up * load(x + (k + 1) * w);
    }
    regular &= keeps(pivot, d);
    const V middle = y / pivot;
    store(x + k * w, middle);
    all_finite = finite(middle);
  }
  for (std::size_t step = 1; step <= meet; ++step) {
    const std::size_t up = meet - step;
    const V above = load(x + up * w) - load(c + up * w) * load(x + (up + 1) * w);
    store(x + up * w, above);
    all_finite &= finite(above);
    if (step <= below) {
      const std::size_t down = meet + step;
      const V under = load(x + down * w) - load(c + down * w) * load(x + (down - 1) * w);
      store(x + down * w, under);
      all_finite &= finite(under);
    }
  }
  const M ok = regular & all_finite;
  for (std::size_t l = 0; l < lanes_in<V>; ++l) {
    solved[half + l] = static_cast<std::uint8_t>(ok[l] != 0);
  }
}

}  // namespace

namespace {
// eliminate_lanes's rows, lanes half.. of each in a V.
template <class V>
struct StoredRows {
  const double* __restrict lower_;
  const double* __restrict diagonal_;
  const double* __restrict upper_;
  const double* __restrict rhs_;
  std::size_t half;
  V lower(std::size_t k) const { return load_as<V>(lower_ + k * lanes + half); }
  V diagonal(std::size_t k) const { return load_as<V>(diagonal_ + k * lanes + half); }
  V upper(std::size_t k) const { return load_as<V>(upper_ + k * lanes + half); }
  V rhs(std::size_t k) const { return load_as<V>(rhs_ + k * lanes + half); }
};
}  // namespace

void eliminate_lanes(std::size_t n, const double* __restrict lower,
                     const double* __restrict diagonal, const double* __restrict upper,
                     const double* __restrict rhs, double* __restrict x, double* __restrict c,
                     std::uint8_t* __restrict solved) {
  in_lane_vectors([&](auto zero, std::size_t half) {
    eliminate_rows<decltype(zero)>(n, StoredRows<decltype(zero)>{lower, diagonal, upper, rhs, half},
                                   half, x, c, solved);
  });
}

}  // namespace deli::rod_passes

namespace deli::rod_passes::across {

// Each pass in explicit vectors of one entry per lane (the autovectoriser leaves loops with
// per-lane accumulators scalar).
namespace {
constexpr std::size_t w = lanes;

template <class V>
inline V absolute(V v) {
  decltype(v < v) bits;
  __builtin_memcpy(&bits, &v, sizeof bits);
  bits &= 0x7fffffffffffffffL;
  __builtin_memcpy(&v, &bits, sizeof v);
  return v;
}
inline Lanes square_root(Lanes v) {
#if defined(__AVX512F__)
  __m512d x;
  __builtin_memcpy(&x, &v, sizeof x);
  x = _mm512_mask_sqrt_pd(x, 0xff, x);  // every lane (a pass-through source: no undefined one)
  __builtin_memcpy(&v, &x, sizeof v);
#else
  for (std::size_t l = 0; l < w; ++l) v[l] = __builtin_sqrt(v[l]);
#endif
  return v;
}
inline void store_lanes(double* out, const Lanes& v) {
  for (std::size_t l = 0; l < w; ++l) out[l] = v[l];
}
const LaneMask all_lanes = broadcast(0.0) == 0.0;

inline Quarter square_root(Quarter v) {
  for (std::size_t l = 0; l < 4; ++l) v[l] = __builtin_sqrt(v[l]);
  return v;
}
}  // namespace

void differences(std::size_t m, const double* x, const double* forward, const double* image,
                 const double* period, const double* limit, double* d, double* d2,
                 std::uint8_t* hold) {
  const std::size_t n = m + 1;
  const std::size_t all = m * w;
  const double px = period[0], py = period[1], pz = period[2];
  const double lx = limit[0], ly = limit[1], lz = limit[2];
  in_lane_vectors([&](auto zero, std::size_t half) {
    using V = decltype(zero);
    auto load = [half](const double* p) { return load_as<V>(p + half); };
    auto store = [half](double* p, const V& v) { store_as<V>(p + half, v); };
    auto within = zero == zero;
    for (std::size_t i = 0; i < all; i += w) {
      const auto f = load(forward + i) > 0;
      const V ax = load(x + i), ay = load(x + n * w + i), az = load(x + 2 * n * w + i);
      const V cx = load(x + i + w), cy = load(x + n * w + i + w), cz = load(x + 2 * n * w + i + w);
      V ex = (f ? ax : cx) - (f ? cx : ax);
      V ey = (f ? ay : cy) - (f ? cy : ay);
      V ez = (f ? az : cz) - (f ? cz : az);
      ex -= px * load(image + i);
      ey -= py * load(image + all + i);
      ez -= pz * load(image + 2 * all + i);
      // Also false for NaN.
      within &= (absolute(ex) <= lx) & (absolute(ey) <= ly) & (absolute(ez) <= lz);
      store(d + i, ex);
      store(d + all + i, ey);
      store(d + 2 * all + i, ez);
      store(d2 + i, ex * ex + ey * ey + ez * ez);
    }
    for (std::size_t l = 0; l < lanes_in<V>; ++l) {
      hold[half + l] = static_cast<std::uint8_t>(within[l] != 0);
    }
  });
}

void held_bound(std::size_t m, const double* d2, const double* length, const double* inverse_length,
                double tolerance, double* per_lane) {
  Lanes largest = broadcast(0.0);
  LaneMask usable = all_lanes;
  for (std::size_t i = 0; i < m * w; i += w) {
    // held_bound_of, lane by lane.
    const Lanes l = load(length + i);
    const Lanes relative_gap = absolute(load(d2 + i) - l * l) * load(inverse_length + i);
    const Lanes rod_bound = relative_gap * (1 + bound_slack) + l * bound_slack;
    usable &= (relative_gap <= 0.25 * l) & (rod_bound <= tolerance);
    // The maximum of the usable bounds (all finite): the same in any order.
    largest = rod_bound > largest ? rod_bound : largest;
  }
  for (std::size_t l = 0; l < w; ++l) per_lane[l] = usable[l] ? largest[l] : __builtin_inf();
}

void normalize_residual(std::size_t m, double* d, double* r, const double* length, double* phi,
                        double* norm, double* merit) {
  const std::size_t all = m * w;
  Lanes largest = broadcast(0.0), squares = broadcast(0.0);
  LaneMask finite = all_lanes;
  for (std::size_t i = 0; i < all; i += w) {
    const Lanes l = square_root(load(r + i));
    const Lanes inverse = 1.0 / l;
    const LaneMask positive = l > 0;
    store(r + i, l);
    store(d + i, positive ? load(d + i) * inverse : 0.0);
    store(d + all + i, positive ? load(d + all + i) * inverse : 0.0);
    store(d + 2 * all + i, positive ? load(d + 2 * all + i) * inverse : 0.0);
    const Lanes p = l - load(length + i);
    store(phi + i, p);
    const Lanes a = absolute(p);
    finite &= (p - p) == 0;
    largest = a > largest ? a : largest;
    squares += p * p;
  }
  for (std::size_t l = 0; l < w; ++l) {
    norm[l] = finite[l] ? largest[l] : __builtin_inf();
    merit[l] = squares[l];
  }
}

namespace {
// bands()' entries, made as the elimination reaches their rows (lanes half.. in a V).
template <class V>
struct BandRows {
  const double* __restrict a;
  const double* __restrict b;
  const double* __restrict w_low;
  const double* __restrict w_high;
  const double* __restrict coupling;
  const double* __restrict phi;
  std::size_t all;
  double scale;
  std::size_t half;
  V at(const double* p) const { return load_as<V>(p + half); }
  V dot(std::size_t k, std::size_t l) const {
    const std::size_t i = k * w, j = l * w;
    return at(a + i) * at(b + j) + at(a + all + i) * at(b + all + j) +
           at(a + 2 * all + i) * at(b + 2 * all + j);
  }
  V diagonal(std::size_t k) const {
    const V d = dot(k, k);
    V entry{};
    entry += 1.0 * at(w_low + k * w) * d;
    entry += 1.0 * at(w_high + k * w) * d;
    return entry * scale;
  }
  V rhs(std::size_t k) const { return -at(phi + k * w); }
  V upper(std::size_t k) const { return (0.0 + at(coupling + k * w) * dot(k, k + 1)) * scale; }
  V lower(std::size_t k) const {
    return (0.0 + at(coupling + (k - 1) * w) * dot(k, k - 1)) * scale;
  }
};
}  // namespace

void solve_bands(std::size_t m, const double* a, const double* b, const double* w_low,
                 const double* w_high, const double* coupling, double scale, const double* phi,
                 double* x, double* c, std::uint8_t* solved) {
  in_lane_vectors([&](auto zero, std::size_t half) {
    eliminate_rows<decltype(zero)>(
        m, BandRows<decltype(zero)>{a, b, w_low, w_high, coupling, phi, m * w, scale, half}, half,
        x, c, solved);
  });
}

namespace {
// One axis of impulse_components.
inline void bead_axis(std::size_t m, const double* uc, const double* z, const double* first_sign,
                      const double* second_sign, double* oc) {
  const std::size_t n = m + 1;
  store(oc, 0.0 + load(uc) * (load(first_sign) * load(z)));
  for (std::size_t i = w; i < (n - 1) * w; i += w) {
    const Lanes sa = load(first_sign + i) * load(z + i - w);
    const Lanes sb = load(second_sign + i) * load(z + i);
    store(oc + i, (0.0 + load(uc + i - w) * sa) + load(uc + i) * sb);
  }
  const std::size_t i = (n - 1) * w;
  store(oc + i, 0.0 + load(uc + i - w) * (load(first_sign + i) * load(z + i - w)));
}
}  // namespace

namespace {
// Bead by bead: (with `place`) z's entry b advanced and bead b placed (all three axes), else
// bead b read from x; then rod b-1 measured from beads b-1 (kept in registers) and b, and
// (with `residual`) normalised with its residual. Each value by the operations of the lanes'
// z + step, positions(), differences(), held_bound() and normalize_residual(), in their order.
template <bool place, bool residual, class V>
void measure_lanes(const Measured& in, std::size_t half, double* x, double* d, double* r,
                   std::uint8_t* hold, double* bound, double* phi, double* norm, double* merit) {
  using M = decltype(V{} < V{});
  constexpr std::size_t v_lanes = sizeof(V) / sizeof(double);
  auto load = [half](const double* p) { return load_as<V>(p + half); };
  auto store = [half](double* p, const V& v) { store_as<V>(p + half, v); };
  const std::size_t m = in.m;
  const std::size_t n = m + 1;
  const std::size_t rods = m * w;
  const std::size_t beads = n * w;
  const double px = in.period[0], py = in.period[1], pz = in.period[2];
  const double lx = in.limit[0], ly = in.limit[1], lz = in.limit[2];
  M taken;
  for (std::size_t l = 0; l < v_lanes; ++l) taken[l] = in.take && in.take[half + l] ? -1L : 0L;
  const M all = V{} == V{};
  M within = all, usable = all, finite = all;
  V largest{}, largest_phi{}, squares{};
  V z_before{}, ux_before{}, uy_before{}, uz_before{};
  V ax{}, ay{}, az{};  // bead b-1
  for (std::size_t b = 0; b < n; ++b) {
    const std::size_t i = b * w;
    V cx, cy, cz;
    if constexpr (place) {
      const double* z = in.z;
      const double* u = in.u;
      V ix, iy, iz;
      if (b < m) {
        const V now = load(z + i);
        const V z_b = taken ? now + load(in.step + i) : now;
        store(in.z + i, z_b);
        const V ux = load(u + i), uy = load(u + rods + i), uz = load(u + 2 * rods + i);
        const V sb = load(in.second_sign + i) * z_b;
        if (b == 0) {
          const V s = load(in.first_sign) * z_b;
          ix = 0.0 + ux * s;
          iy = 0.0 + uy * s;
          iz = 0.0 + uz * s;
        } else {
          const V sa = load(in.first_sign + i) * z_before;
          ix = (0.0 + ux_before * sa) + ux * sb;
          iy = (0.0 + uy_before * sa) + uy * sb;
          iz = (0.0 + uz_before * sa) + uz * sb;
        }
        z_before = z_b;
        ux_before = ux;
        uy_before = uy;
        uz_before = uz;
      } else {
        const V sa = load(in.first_sign + i) * z_before;
        ix = 0.0 + ux_before * sa;
        iy = 0.0 + uy_before * sa;
        iz = 0.0 + uz_before * sa;
      }
      if (in.impulse) {
        store(in.impulse + i, ix);
        store(in.impulse + beads + i, iy);
        store(in.impulse + 2 * beads + i, iz);
      }
      const V h = load(in.hw + i);
      cx = load(in.x0 + i) + ix * h;
      cy = load(in.x0 + beads + i) + iy * h;
      cz = load(in.x0 + 2 * beads + i) + iz * h;
      store(x + i, cx);
      store(x + beads + i, cy);
      store(x + 2 * beads + i, cz);
    } else {
      cx = load(x + i);
      cy = load(x + beads + i);
      cz = load(x + 2 * beads + i);
    }
    if (b > 0) {
      const std::size_t k = i - w;  // rod b-1
      const M f = load(in.forward + k) > 0;
      V ex = (f ? ax : cx) - (f ? cx : ax);
      V ey = (f ? ay : cy) - (f ? cy : ay);
      V ez = (f ? az : cz) - (f ? cz : az);
      ex -= px * load(in.image + k);
      ey -= py * load(in.image + rods + k);
      ez -= pz * load(in.image + 2 * rods + k);
      within &= (absolute(ex) <= lx) & (absolute(ey) <= ly) & (absolute(ez) <= lz);
      const V r2 = ex * ex + ey * ey + ez * ez;
      const V l = load(in.length + k);
      const V relative_gap = absolute(r2 - l * l) * load(in.inverse_length + k);
      const V rod_bound = relative_gap * (1 + bound_slack) + l * bound_slack;
      usable &= (relative_gap <= 0.25 * l) & (rod_bound <= in.tolerance);
      largest = rod_bound > largest ? rod_bound : largest;
      if constexpr (residual) {
        const V length = square_root(r2);
        const V inverse = 1.0 / length;
        const M positive = length > 0;
        store(r + k, length);
        store(d + k, positive ? ex * inverse : 0.0);
        store(d + rods + k, positive ? ey * inverse : 0.0);
        store(d + 2 * rods + k, positive ? ez * inverse : 0.0);
        const V p = length - l;
        store(phi + k, p);
        finite &= (p - p) == 0;
        const V magnitude_p = absolute(p);
        largest_phi = magnitude_p > largest_phi ? magnitude_p : largest_phi;
        squares += p * p;
      } else {
        store(d + k, ex);
        store(d + rods + k, ey);
        store(d + 2 * rods + k, ez);
        store(r + k, r2);
      }
    }
    ax = cx;
    ay = cy;
    az = cz;
  }
  for (std::size_t l = 0; l < v_lanes; ++l) {
    hold[half + l] = static_cast<std::uint8_t>(within[l] != 0);
    bound[half + l] = usable[l] ? largest[l] : __builtin_inf();
    if constexpr (residual) {
      norm[half + l] = finite[l] ? largest_phi[l] : __builtin_inf();
      merit[half + l] = squares[l];
    }
  }
}

// In vectors of four lanes where the CPU has AVX2 and not AVX-512 (in_lane_vectors).
template <bool place, bool residual>
void measure(const Measured& in, double* x, double* d, double* r, std::uint8_t* hold, double* bound,
             double* phi, double* norm, double* merit) {
  in_lane_vectors([&](auto zero, std::size_t half) {
    measure_lanes<place, residual, decltype(zero)>(in, half, x, d, r, hold, bound, phi, norm,
                                                   merit);
  });
}
}  // namespace

void advance_and_measure(const Measured& in, double* x, double* d, double* r, std::uint8_t* hold,
                         double* bound, double* phi, double* norm, double* merit) {
  if (phi) {
    measure<true, true>(in, x, d, r, hold, bound, phi, norm, merit);
  } else {
    measure<true, false>(in, x, d, r, hold, bound, phi, norm, merit);
  }
}

void measure_residual(const Measured& in, const double* x, double* d, double* r, std::uint8_t* hold,
                      double* bound, double* phi, double* norm, double* merit) {
  measure<false, true>(in, const_cast<double*>(x), d, r, hold, bound, phi, norm, merit);
}

void impulses(std::size_t m, const double* u, const double* z, const double* first_sign,
              const double* second_sign, double* out) {
  const std::size_t n = m + 1;
  for (std::size_t c = 0; c < 3; ++c) {
    bead_axis(m, u + c * m * w, z, first_sign, second_sign, out + c * n * w);
  }
}

namespace {
template <class V>
void project_rows_lanes(std::size_t half, std::size_t m, double* d, double* r, const double* length,
                        const double* v, const double* low_first, const double* low_sign,
                        const double* high_sign, const double* w_low, const double* w_high,
                        const double* coupling, double* largest_deviation, double* lower,
                        double* diagonal, double* upper, double* rhs) {
  using M = decltype(V{} < V{});
  constexpr std::size_t v_lanes = sizeof(V) / sizeof(double);
  auto load = [half](const double* p) { return load_as<V>(p + half); };
  auto store = [half](double* p, const V& v) { store_as<V>(p + half, v); };
  const std::size_t n = m + 1;
  const std::size_t all = m * w;
  constexpr double scale = 1.0;
  V largest = V{};
  V px = largest, py = largest, pz = largest;  // rod k-1's direction
  for (std::size_t i = 0; i < all; i += w) {
    // normalize()
    const V l = square_root(load(r + i));
    const V inverse = 1.0 / l;
    const M positive = l > 0;
    store(r + i, l);
    const V ux = positive ? load(d + i) * inverse : 0.0;
    const V uy = positive ? load(d + all + i) * inverse : 0.0;
    const V uz = positive ? load(d + 2 * all + i) * inverse : 0.0;
    store(d + i, ux);
    store(d + all + i, uy);
    store(d + 2 * all + i, uz);
    // largest_deviation()
    const V length_k = load(length + i);
    const V deviation = absolute(l - length_k) / length_k;
    largest = largest < deviation ? deviation : largest;
    // projections()
    const M f = load(low_first + i) > 0;
    const V ax = load(v + i), ay = load(v + n * w + i), az = load(v + 2 * n * w + i);
    const V cx = load(v + i + w), cy = load(v + n * w + i + w), cz = load(v + 2 * n * w + i + w);
    const V to_low = ux * (f ? ax : cx) + uy * (f ? ay : cy) + uz * (f ? az : cz);
    const V to_high = ux * (f ? cx : ax) + uy * (f ? cy : ay) + uz * (f ? cz : az);
    V projected = V{};
    projected += load(low_sign + i) * to_low;
    projected += load(high_sign + i) * to_high;
    // bands() with a = b = u: the diagonal and right-hand side, then the entries between
    // rods k-1 and k.
    const V dd = ux * ux + uy * uy + uz * uz;
    V entry = V{};
    entry += 1.0 * load(w_low + i) * dd;
    entry += 1.0 * load(w_high + i) * dd;
    store(diagonal + i, entry * scale);
    store(rhs + i, -projected);
    if (i > 0) {
      const std::size_t before = i - w;
      const V c = load(coupling + before);
      const V up = px * ux + py * uy + pz * uz;
      store(upper + before, (0.0 + c * up) * scale);
      const V down = ux * px + uy * py + uz * pz;
      store(lower + i, (0.0 + c * down) * scale);
    }
    px = ux;
    py = uy;
    pz = uz;
  }
  for (std::size_t l = 0; l < v_lanes; ++l) largest_deviation[half + l] = largest[l];
}

}  // namespace

// In vectors of four lanes where the CPU has AVX2 and not AVX-512 (in_lane_vectors).
void project_rows(std::size_t m, double* d, double* r, const double* length, const double* v,
                  const double* low_first, const double* low_sign, const double* high_sign,
                  const double* w_low, const double* w_high, const double* coupling,
                  double* largest_deviation, double* lower, double* diagonal, double* upper,
                  double* rhs) {
  in_lane_vectors([&](auto zero, std::size_t half) {
    project_rows_lanes<decltype(zero)>(half, m, d, r, length, v, low_first, low_sign, high_sign,
                                       w_low, w_high, coupling, largest_deviation, lower, diagonal,
                                       upper, rhs);
  });
}

void virial(std::size_t m, const double* z, const double* r, double* per_lane) {
  Lanes sum = broadcast(0.0);
  for (std::size_t i = 0; i < m * w; i += w) sum += load(z + i) * load(r + i);
  store_lanes(per_lane, sum);
}

namespace {
// Rows v[0..8) of an 8 x 8 block transposed in place (v[c][r] = old v[r][c]): three rounds
// of two-source shuffles, moving numbers without changing them.
inline void transpose(Lanes (&v)[w]) {
  static_assert(w == 8);
  Lanes s[w], t[w];
  for (std::size_t i = 0; i < w; i += 2) {
    s[i] = shuffle<0, 8, 2, 10, 4, 12, 6, 14>(v[i], v[i + 1]);
    s[i + 1] = shuffle<1, 9, 3, 11, 5, 13, 7, 15>(v[i], v[i + 1]);
  }
  for (std::size_t i = 0; i < w; i += 4) {
    for (std::size_t o = 0; o < 2; ++o) {
      t[i + o] = shuffle<0, 1, 8, 9, 4, 5, 12, 13>(s[i + o], s[i + o + 2]);
      t[i + o + 2] = shuffle<2, 3, 10, 11, 6, 7, 14, 15>(s[i + o], s[i + o + 2]);
    }
  }
  for (std::size_t c = 0; c < 4; ++c) {
    v[c] = shuffle<0, 1, 2, 3, 8, 9, 10, 11>(t[c], t[c + 4]);
    v[c + 4] = shuffle<4, 5, 6, 7, 12, 13, 14, 15>(t[c], t[c + 4]);
  }
}

// Under kQuarterLanes the 8 x 8 blocks move as four 4 x 4 blocks of Quarters: as Lanes, two
// blocks' rows and the shuffles' temporaries did not fit the sixteen registers (gather_sum:
// 1365 stack references among 2738 instructions). Rows v[0..4) transposed in place.
inline void transpose(Quarter (&v)[4]) {
  const Quarter s0 = shuffle4<0, 4, 2, 6>(v[0], v[1]), s1 = shuffle4<1, 5, 3, 7>(v[0], v[1]);
  const Quarter s2 = shuffle4<0, 4, 2, 6>(v[2], v[3]), s3 = shuffle4<1, 5, 3, 7>(v[2], v[3]);
  v[0] = shuffle4<0, 1, 4, 5>(s0, s2);
  v[1] = shuffle4<0, 1, 4, 5>(s1, s3);
  v[2] = shuffle4<2, 3, 6, 7>(s0, s2);
  v[3] = shuffle4<2, 3, 6, 7>(s1, s3);
}
// Lanes h..h+3 of numbers j..j+3 of consecutive chains (lane l's number j at l numbers + j)
// as four Quarters, one a number (the 4 x 4 block transposed).
inline void load_quarter_block(const double* __restrict src, std::size_t numbers, std::size_t j,
                               std::size_t h, Quarter (&q)[4]) {
  for (std::size_t l = 0; l < 4; ++l) q[l] = load_as<Quarter>(src + (h + l) * numbers + j);
  if constexpr (kQuarterLanes) transpose(q);
}

// Numbers j..j+w-1 of two arrays (as load_quarter_block reads them) in 4 x 4 blocks of
// Quarters: visit(i, h, u, v) for number i and lanes h..h+3, u from a and v from b.
template <class Visit>
inline void for_each_quarter_pair(const double* __restrict a, const double* __restrict b,
                                  std::size_t numbers, std::size_t j, Visit&& visit) {
  for (std::size_t g = 0; g < w; g += 4) {
    for (std::size_t h = 0; h < w; h += 4) {
      Quarter u[4], v[4];
      load_quarter_block(a, numbers, j + g, h, u);
      load_quarter_block(b, numbers, j + g, h, v);
      for (std::size_t k = 0; k < 4; ++k) visit(j + g + k, h, u[k], v[k]);
    }
  }
}

// Lane l's chain at particles base + l n .. (consecutive chains of n beads): its numbers
// are the doubles 3 (base + l n) + j, j < 3n, j = 3 bead + axis. The across layout holds
// number j of every lane in row row_of(n, j) = axis n + bead, one vector. Blocks of 8 numbers
// of the 8 lanes move as 8 x 8 transposes, the numbers past the last whole block one by one.
inline std::size_t row_of(std::size_t n, std::size_t j) {
  return (j % 3) * n + j / 3;
}

// Lane l's particle row[l]: its three numbers (3 doubles a particle in `all`) into lane l of
// vx, vy and vz.
inline void gather_row(const std::int32_t* __restrict row, const double* __restrict all, Lanes& vx,
                       Lanes& vy, Lanes& vz) {
  for (std::size_t l = 0; l < w; ++l) {
    const std::size_t g = 3 * static_cast<std::size_t>(row[l]);
    vx[l] = all[g];
    vy[l] = all[g + 1];
    vz[l] = all[g + 2];
  }
}

// Bead `bead`'s three rows of the across layout (n beads) from vx, vy and vz.
inline void store_bead(double* __restrict out, std::size_t n, std::size_t bead, const Lanes& vx,
                       const Lanes& vy, const Lanes& vz) {
  store(out + bead * w, vx);
  store(out + (n + bead) * w, vy);
  store(out + (2 * n + bead) * w, vz);
}
}  // namespace

// Per row of lanes: the particles' entries loaded one by one into vectors, stored whole (the
// rows' stores fill their cache lines; the lane-by-lane copies wrote one double per line).
// Consecutive chains (base >= 0): by 8 x 8 blocks. a and b are moved apart and added in the
// across layout: the same sums as added in the particles' (the moves change no number).
void gather_sum(std::size_t n, const std::int32_t* __restrict particle, std::int64_t base,
                const double* __restrict a, const double* __restrict b, double* __restrict out,
                const double* __restrict memo, std::uint8_t* __restrict same) {
  // The bits of b against memo's, lanes whose bits differ anywhere set.
  LaneMask differ = {};
  auto compare = [&](std::size_t row, const Lanes& v) {
    if (memo) differ |= bits(v) != bits(load(memo + row * w));
  };
  if (base >= 0) {
    const std::size_t numbers = 3 * n;
    const double* __restrict a0 = a + 3 * base;
    const double* __restrict b0 = b + 3 * base;
    std::size_t j = 0;
    for (; kQuarterLanes && j + w <= numbers; j += w) {
      for_each_quarter_pair(a0, b0, numbers, j,
                            [&](std::size_t i, std::size_t h, const Quarter& u, const Quarter& v) {
                              const std::size_t r = row_of(n, i);
                              store_as(out + r * w + h, u + v);
                              if (memo) {
                                const auto d = bits(v) != bits(load_as<Quarter>(memo + r * w + h));
                                for (std::size_t l = 0; l < 4; ++l) differ[h + l] |= d[l];
                              }
                            });
    }
    for (; j + w <= numbers; j += w) {
      Lanes u[w], v[w];
      for (std::size_t l = 0; l < w; ++l) {
        u[l] = load(a0 + l * numbers + j);
        v[l] = load(b0 + l * numbers + j);
      }
      transpose(u);
      transpose(v);
      for (std::size_t k = 0; k < w; ++k) {
        const std::size_t r = row_of(n, j + k);
        store(out + r * w, u[k] + v[k]);
        compare(r, v[k]);
      }
    }
    for (; j < numbers; ++j) {
      const std::size_t r = row_of(n, j);
      Lanes v;
      for (std::size_t l = 0; l < w; ++l) {
        v[l] = b0[l * numbers + j];
        out[r * w + l] = a0[l * numbers + j] + v[l];
      }
      compare(r, v);
    }
  } else {
    for (std::size_t bead = 0; bead < n; ++bead) {
      const std::int32_t* __restrict row = particle + bead * w;
      Lanes ax, ay, az, bx, by, bz;
      gather_row(row, a, ax, ay, az);
      gather_row(row, b, bx, by, bz);
      store_bead(out, n, bead, ax + bx, ay + by, az + bz);
      compare(bead, bx);
      compare(n + bead, by);
      compare(2 * n + bead, bz);
    }
  }
  if (same) {
    for (std::size_t l = 0; l < w; ++l) same[l] = static_cast<std::uint8_t>(memo && differ[l] == 0);
  }
}

void gather_velocities(std::size_t n, const std::int32_t* __restrict particle, std::int64_t base,
                       const double* __restrict x, const double* __restrict p,
                       const double* __restrict inverse_mass, double* __restrict x_out,
                       double* __restrict v_out) {
  if (base >= 0) {
    const std::size_t numbers = 3 * n;
    const double* __restrict x0 = x + 3 * base;
    const double* __restrict p0 = p + 3 * base;
    std::size_t j = 0;
    for (; kQuarterLanes && j + w <= numbers; j += w) {
      for_each_quarter_pair(x0, p0, numbers, j,
                            [&](std::size_t i, std::size_t h, const Quarter& u, const Quarter& v) {
                              const std::size_t r = row_of(n, i);
                              store_as(x_out + r * w + h, u);
                              store_as(v_out + r * w + h,
                                       v * load_as<Quarter>(inverse_mass + (i / 3) * w + h));
                            });
    }
    for (; j + w <= numbers; j += w) {
      Lanes u[w], v[w];
      for (std::size_t l = 0; l < w; ++l) {
        u[l] = load(x0 + l * numbers + j);
        v[l] = load(p0 + l * numbers + j);
      }
      transpose(u);
      transpose(v);
      for (std::size_t k = 0; k < w; ++k) {
        const std::size_t r = row_of(n, j + k);
        store(x_out + r * w, u[k]);
        store(v_out + r * w, v[k] * load(inverse_mass + ((j + k) / 3) * w));
      }
    }
    for (; j < numbers; ++j) {
      const std::size_t r = row_of(n, j);
      for (std::size_t l = 0; l < w; ++l) {
        x_out[r * w + l] = x0[l * numbers + j];
        v_out[r * w + l] = p0[l * numbers + j] * inverse_mass[(j / 3) * w + l];
      }
    }
    return;
  }
  for (std::size_t bead = 0; bead < n; ++bead) {
    const std::int32_t* __restrict row = particle + bead * w;
    Lanes xx, xy, xz, px, py, pz;
    gather_row(row, x, xx, xy, xz);
    gather_row(row, p, px, py, pz);
    const Lanes weight = load(inverse_mass + bead * w);
    store_bead(x_out, n, bead, xx, xy, xz);
    store_bead(v_out, n, bead, px * weight, py * weight, pz * weight);
  }
}

namespace {
template <bool add>
void scatter_rows(std::size_t n, const std::int32_t* __restrict particle, std::int64_t base,
                  const double* __restrict in, const std::uint8_t* __restrict take,
                  double* __restrict out) {
  bool every = true;
  for (std::size_t l = 0; l < w; ++l) every = every && take[l];
  if (base >= 0 && every) {
    const std::size_t numbers = 3 * n;
    double* __restrict o = out + 3 * base;
    std::size_t j = 0;
    for (; kQuarterLanes && j + w <= numbers; j += w) {
      for (std::size_t g = 0; g < w; g += 4) {
        for (std::size_t h = 0; h < w; h += 4) {
          // Rows j+g.. of lanes h..h+3, transposed: lane h+l's numbers j+g..j+g+3.
          Quarter v[4];
          for (std::size_t k = 0; k < 4; ++k) {
            v[k] = load_as<Quarter>(in + row_of(n, j + g + k) * w + h);
          }
          if constexpr (kQuarterLanes) transpose(v);
          for (std::size_t l = 0; l < 4; ++l) {
            double* __restrict at = o + (h + l) * numbers + j + g;
            if constexpr (add) {
              store_as(at, load_as<Quarter>(at) + v[l]);
            } else {
              store_as(at, v[l]);
            }
          }
        }
      }
    }
    for (; j + w <= numbers; j += w) {
      Lanes v[w];
      for (std::size_t k = 0; k < w; ++k) v[k] = load(in + row_of(n, j + k) * w);
      transpose(v);
      for (std::size_t l = 0; l < w; ++l) {
        double* __restrict at = o + l * numbers + j;
        if constexpr (add) {
          store(at, load(at) + v[l]);
        } else {
          store(at, v[l]);
        }
      }
    }
    for (; j < numbers; ++j) {
      for (std::size_t l = 0; l < w; ++l) {
        if constexpr (add) {
          o[l * numbers + j] += in[row_of(n, j) * w + l];
        } else {
          o[l * numbers + j] = in[row_of(n, j) * w + l];
        }
      }
    }
    return;
  }
  for (std::size_t bead = 0; bead < n; ++bead) {
    const std::int32_t* __restrict row = particle + bead * w;
    const Lanes x = load(in + bead * w), y = load(in + (n + bead) * w),
                z = load(in + (2 * n + bead) * w);
    for (std::size_t l = 0; l < w; ++l) {
      if (!take[l]) continue;
      double* __restrict o = out + 3 * static_cast<std::size_t>(row[l]);
      if constexpr (add) {
        o[0] += x[l];
        o[1] += y[l];
        o[2] += z[l];
      } else {
        o[0] = x[l];
        o[1] = y[l];
        o[2] = z[l];
      }
    }
  }
}
}  // namespace

void scatter(std::size_t n, const std::int32_t* particle, std::int64_t base, const double* in,
             const std::uint8_t* take, bool add, double* out) {
  if (add) {
    scatter_rows<true>(n, particle, base, in, take, out);
  } else {
    scatter_rows<false>(n, particle, base, in, take, out);
  }
}

}  // namespace deli::rod_passes::across
