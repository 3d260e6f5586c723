#include "solvers/rod_chain_passes.hpp"

namespace deli::rod_passes {

// __restrict: the arrays never overlap, so the loops vectorise without runtime alias checks.
// Builtins instead of std::sqrt and std::abs: no inline library code shared with files
// built for another CPU.

namespace {
// differences() with a pointer per axis (restrict: no runtime overlap checks).
inline bool differences_by_axis(std::size_t m, const double* __restrict bx,
                                const double* __restrict by, const double* __restrict bz,
                                const double* __restrict forward, const double* __restrict ix,
                                const double* __restrict iy, const double* __restrict iz,
                                const double* __restrict period, const double* __restrict limit,
                                double* __restrict dx, double* __restrict dy, double* __restrict dz,
                                double* __restrict d2) {
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
    d2[k] = ex * ex + ey * ey + ez * ez;
  }
  return hold != 0;
}
}  // namespace

bool differences(std::size_t m, const double* x, const double* forward, const double* image,
                 const double* period, const double* limit, double* d, double* d2) {
  const std::size_t n = m + 1;
  return differences_by_axis(m, x, x + n, x + 2 * n, forward, image, image + m, image + 2 * m,
                             period, limit, d, d + m, d + 2 * m, d2);
}

void normalize(std::size_t m, double* __restrict d, double* __restrict r) {
  for (std::size_t k = 0; k < m; ++k) {
    const double length = __builtin_sqrt(r[k]);
    const double inverse = 1.0 / length;
    const bool positive = length > 0;
    r[k] = length;
    d[k] = positive ? d[k] * inverse : 0.0;
    d[m + k] = positive ? d[m + k] * inverse : 0.0;
    d[2 * m + k] = positive ? d[2 * m + k] * inverse : 0.0;
  }
}

void held_bounds(std::size_t m, const double* __restrict d2, const double* __restrict length,
                 const double* __restrict inverse_length, double tolerance,
                 double* __restrict bound, std::uint8_t* __restrict usable) {
  constexpr double slack = 0x1p-50;
  for (std::size_t k = 0; k < m; ++k) {
    const double l = length[k];
    const double relative_gap = __builtin_fabs(d2[k] - l * l) * inverse_length[k];
    const double rod_bound = relative_gap * (1 + slack) + l * slack;
    bound[k] = rod_bound;
    // Also false for NaN.
    usable[k] = static_cast<std::uint8_t>((relative_gap <= 0.25 * l) & (rod_bound <= tolerance));
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

void positions(std::size_t m, const double* __restrict x0, const double* u, const double* z,
               const double* first_sign, const double* second_sign, const double* __restrict hw,
               double* __restrict out) {
  const std::size_t n = m + 1;
  impulse_components(m, u, z, first_sign, second_sign, out, out + n, out + 2 * n);
  for (std::size_t c = 0; c < 3; ++c) {
    for (std::size_t b = 0; b < n; ++b) out[c * n + b] = x0[c * n + b] + out[c * n + b] * hw[b];
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

// The lane helpers below take and return vectors by value: internal and inlined, so the
// warning that such an ABI differs between targets concerns no call that exists.
#pragma GCC diagnostic ignored "-Wpsabi"
namespace {
// One entry per lane: GCC's vector extension, element-wise IEEE operations at whatever
// width the target has (two SSE2 halves per 128 bits, one AVX-512 register).
typedef double Lanes __attribute__((vector_size(lanes * sizeof(double))));
typedef long LaneMask __attribute__((vector_size(lanes * sizeof(double))));
static_assert(sizeof(long) == sizeof(double));

inline Lanes load(const double* p) {
  Lanes v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void store(double* p, const Lanes& v) {
  __builtin_memcpy(p, &v, sizeof v);
}
// |v| but for the sign of a zero (only compared here); NaN stays NaN.
inline Lanes magnitude(const Lanes& v) {
  return v < 0 ? -v : v;
}
// A pivot lost to cancellation (relative to its diagonal entry) means dependent rows: all
// ones where it is not.
inline LaneMask keeps(const Lanes& pivot, const Lanes& diagonal_entry) {
  return magnitude(pivot) > 1e-12 * magnitude(diagonal_entry);
}
// All ones where v is finite (v - v is 0 exactly then, NaN otherwise).
inline LaneMask finite(const Lanes& v) {
  return (v - v) == 0;
}
}  // namespace

void eliminate_lanes(std::size_t n, const double* __restrict lower,
                     const double* __restrict diagonal, const double* __restrict upper,
                     const double* __restrict rhs, double* __restrict x, double* __restrict c,
                     std::uint8_t* __restrict solved) {
  constexpr std::size_t w = lanes;
  if (n == 0) {
    for (std::size_t l = 0; l < w; ++l) solved[l] = 1;
    return;
  }
  LaneMask regular = {};
  regular = regular == 0;  // all ones
  const std::size_t meet = n / 2;
  const std::size_t below = n - 1 - meet;
  for (std::size_t step = 0; step < meet; ++step) {
    {
      const std::size_t k = step;
      const Lanes d = load(diagonal + k * w);
      Lanes pivot = d, y = load(rhs + k * w);
      if (k > 0) {
        const Lanes lo = load(lower + k * w);
        pivot = d - lo * load(c + (k - 1) * w);
        y -= lo * load(x + (k - 1) * w);
      }
      regular &= keeps(pivot, d);
      const Lanes reciprocal = 1.0 / pivot;
      store(c + k * w, load(upper + k * w) * reciprocal);
      store(x + k * w, y * reciprocal);
    }
    if (step < below) {
      const std::size_t k = n - 1 - step;
      const Lanes d = load(diagonal + k * w);
      Lanes pivot = d, y = load(rhs + k * w);
      if (k < n - 1) {
        const Lanes up = load(upper + k * w);
        pivot = d - up * load(c + (k + 1) * w);
        y -= up * load(x + (k + 1) * w);
      }
      regular &= keeps(pivot, d);
      const Lanes reciprocal = 1.0 / pivot;
      store(c + k * w, load(lower + k * w) * reciprocal);
      store(x + k * w, y * reciprocal);
    }
  }
  LaneMask all_finite;
  {
    const std::size_t k = meet;
    const Lanes d = load(diagonal + k * w);
    Lanes pivot = d, y = load(rhs + k * w);
    if (k > 0) {
      const Lanes lo = load(lower + k * w);
      pivot -= lo * load(c + (k - 1) * w);
      y -= lo * load(x + (k - 1) * w);
    }
    if (k < n - 1) {
      const Lanes up = load(upper + k * w);
      pivot -= up * load(c + (k + 1) * w);
      y -= up * load(x + (k + 1) * w);
    }
    regular &= keeps(pivot, d);
    const Lanes middle = y / pivot;
    store(x + k * w, middle);
    all_finite = finite(middle);
  }
  for (std::size_t step = 1; step <= meet; ++step) {
    const std::size_t up = meet - step;
    const Lanes above = load(x + up * w) - load(c + up * w) * load(x + (up + 1) * w);
    store(x + up * w, above);
    all_finite &= finite(above);
    if (step <= below) {
      const std::size_t down = meet + step;
      const Lanes under = load(x + down * w) - load(c + down * w) * load(x + (down - 1) * w);
      store(x + down * w, under);
      all_finite &= finite(under);
    }
  }
  const LaneMask ok = regular & all_finite;
  for (std::size_t l = 0; l < w; ++l) solved[l] = static_cast<std::uint8_t>(ok[l] != 0);
}

}  // namespace deli::rod_passes
