#include "integrators/gvi_particle_passes.hpp"

#include <algorithm>
#include <type_traits>

#include "core/lane_vectors.hpp"

namespace deli::gvi_passes {

namespace {
using namespace lane_vectors;  // Lanes, LaneMask, Quarter, load_as, store_as, shuffles
// Eight particles a block (four where kQuarterLanes: an AVX2 CPU without AVX-512, where a
// pass's eight-lane vectors, two registers each, did not fit the sixteen and were spilled):
// their numbers are three vectors of a block's width, and a value per particle one vector.
// Each particle's operations are the same either way.
using Block = std::conditional_t<kQuarterLanes, Quarter, Lanes>;
using BlockMask = decltype(Block{} < Block{});
constexpr std::size_t w = lanes_in<Block>;
inline Block load(const double* p) {
  return load_as<Block>(p);
}
inline void store(double* p, const Block& v) {
  store_as(p, v);
}
inline Block broadcast(double v) {
  Block out;
  for (std::size_t l = 0; l < w; ++l) out[l] = v;
  return out;
}

// The block's three vectors of numbers: particle j's x, y, z are entries 3j, 3j+1, 3j+2 of
// the 3w (vector e / w, entry e % w).
template <class V>
struct TriplesOf {
  V v[3];
};
using Triples = TriplesOf<Block>;
inline void store_triples(double* p, const Triples& t) {
  for (std::size_t k = 0; k < 3; ++k) store(p + k * w, t.v[k]);
}
// A value per particle at each of its three numbers.
[[maybe_unused]] inline TriplesOf<Lanes> spread(const Lanes& v) {
  return {{shuffle<0, 0, 0, 1, 1, 1, 2, 2>(v, v), shuffle<2, 3, 3, 3, 4, 4, 4, 5>(v, v),
           shuffle<5, 5, 6, 6, 6, 7, 7, 7>(v, v)}};
}
[[maybe_unused]] inline TriplesOf<Quarter> spread(const Quarter& v) {
  return {{shuffle4<0, 0, 0, 1>(v, v), shuffle4<1, 1, 2, 2>(v, v), shuffle4<2, 3, 3, 3>(v, v)}};
}
// Per particle, dot(d, d) = d.x d.x + d.y d.y + d.z d.z in that order (vec3.hpp's norm2).
[[maybe_unused]] inline Lanes norm2s(const TriplesOf<Lanes>& d) {
  const Lanes a = d.v[0] * d.v[0], b = d.v[1] * d.v[1], c = d.v[2] * d.v[2];
  const Lanes x = shuffle<0, 1, 2, 3, 4, 5, 10, 13>(shuffle<0, 3, 6, 9, 12, 15, 0, 0>(a, b), c);
  const Lanes y = shuffle<0, 1, 2, 3, 4, 8, 11, 14>(shuffle<1, 4, 7, 10, 13, 0, 0, 0>(a, b), c);
  const Lanes z = shuffle<0, 1, 2, 3, 4, 9, 12, 15>(shuffle<2, 5, 8, 11, 14, 0, 0, 0>(a, b), c);
  return (x + y) + z;
}
// The four particles' x, y, z: entries 0 3 6 9, 1 4 7 10 and 2 5 8 11 of a, b, c in a row.
[[maybe_unused]] inline Quarter norm2s(const TriplesOf<Quarter>& d) {
  const Quarter a = d.v[0] * d.v[0], b = d.v[1] * d.v[1], c = d.v[2] * d.v[2];
  const Quarter x = shuffle4<0, 1, 2, 5>(shuffle4<0, 3, 6, 0>(a, b), c);
  const Quarter y = shuffle4<0, 1, 2, 6>(shuffle4<1, 4, 7, 0>(a, b), c);
  const Quarter z = shuffle4<0, 1, 4, 7>(shuffle4<2, 5, 0, 0>(a, b), c);
  return (x + y) + z;
}
// 1 where !(value <= limit), else 0 (a comparison's true is all ones, -1).
inline BlockMask missed(const Block& value, const Block& limit) {
  return (value <= limit) + 1;
}
// Each lane's square root (correctly rounded; built without errno, so in vectors).
inline Block roots(Block v) {
  for (std::size_t l = 0; l < w; ++l) v[l] = __builtin_sqrt(v[l]);
  return v;
}
inline std::size_t total(const BlockMask& counts) {
  std::size_t sum = 0;
  for (std::size_t l = 0; l < w; ++l) sum += static_cast<std::size_t>(counts[l]);
  return sum;
}
// The scalar form of the passes, for the particles after the last whole block.
struct Three {
  double x, y, z;
};
inline Three at(const double* p, std::size_t i) {
  return {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
}
inline void put(double* p, std::size_t i, const Three& v) {
  p[3 * i] = v.x;
  p[3 * i + 1] = v.y;
  p[3 * i + 2] = v.z;
}
inline double norm2(const Three& d) {
  return d.x * d.x + d.y * d.y + d.z * d.z;
}
}  // namespace

StepStartTally step_start(const StepStart& pass, std::size_t begin, std::size_t end) {
  const double h = pass.h;
  const double kick = 0.5 * h;
  const double* __restrict position = pass.position;
  const double* __restrict velocity = pass.velocity;
  const double* __restrict mass = pass.mass;
  const double* __restrict force = pass.force;
  const double* __restrict at_build = pass.at_build;
  double* __restrict q = pass.q;
  double* __restrict displacement2 = pass.predicted ? pass.displacement2 : nullptr;
  double* __restrict reach = displacement2 ? pass.reach : nullptr;
  double* __restrict reach_limit2 = pass.reach_limit2;
  const double* __restrict anchor = reach ? pass.anchor : nullptr;
  double* __restrict moved_from_anchor = pass.moved;
  const double floor2 = pass.reach_floor2, tolerance = pass.gap_tolerance;
  const double half_tolerance = 0.5 * tolerance;
  BlockMask outside = {};
  const Block limit = broadcast(pass.list_limit2), floor2s = broadcast(floor2);
  Block largest = broadcast(0.0), anchored_largest = broadcast(0.0);
  std::size_t i = begin;
  for (; i + w <= end; i += w) {
    const std::size_t o = 3 * i;
    const Block m = load(mass + i);
    const Triples ms = spread(m), hms = spread(h / m);
    Triples momentum, half, d, x, moved, displaced, anchored;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t e = o + k * w;
      const Block start = load(position + e);
      store(q + e, start);
      momentum.v[k] = load(velocity + e) * ms.v[k];
      half.v[k] = momentum.v[k] + load(force + e) * kick;
      d.v[k] = half.v[k] * hms.v[k];
      x.v[k] = start + d.v[k];
      if (at_build) moved.v[k] = x.v[k] - load(at_build + e);
      if (displacement2) displaced.v[k] = x.v[k] - start;
      if (anchor) anchored.v[k] = start - load(anchor + e);
    }
    if (displacement2) {
      const Block moved2 = norm2s(displaced);
      store(displacement2 + i, moved2);
      largest = largest < moved2 ? moved2 : largest;
      if (reach) {
        const Block own = roots(moved2 < floor2s ? floor2s : moved2) * 2.0 + tolerance;
        store(reach + i, own);
        const Block inner = own - half_tolerance;
        store(reach_limit2 + i, inner * inner);
        if (anchor) {
          const Block anchored2 = norm2s(anchored);
          anchored_largest = anchored_largest < anchored2 ? anchored2 : anchored_largest;
          store(moved_from_anchor + i, roots(anchored2) + own);
        }
      }
    }
    if (pass.p) store_triples(pass.p + o, momentum);
    if (pass.p_start) store_triples(pass.p_start + o, momentum);
    if (pass.half) store_triples(pass.half + o, half);
    if (pass.free) store_triples(pass.free + o, d);
    if (pass.impulse) store_triples(pass.impulse + o, Triples{});
    if (pass.predicted) store_triples(pass.predicted + o, x);
    if (at_build) outside += missed(norm2s(moved), limit);
  }
  StepStartTally tally;
  tally.beyond_list = total(outside);
  for (std::size_t l = 0; l < w; ++l) {
    tally.largest2 = tally.largest2 < largest[l] ? largest[l] : tally.largest2;
    tally.anchored_largest2 = tally.anchored_largest2 < anchored_largest[l]
                                  ? anchored_largest[l]
                                  : tally.anchored_largest2;
  }
  for (; i < end; ++i) {
    const double m = mass[i];
    const Three start = at(position, i), v = at(velocity, i), f = at(force, i);
    put(q, i, start);
    const Three momentum{v.x * m, v.y * m, v.z * m};
    const Three half{momentum.x + f.x * kick, momentum.y + f.y * kick, momentum.z + f.z * kick};
    const double hm = h / m;
    const Three d{half.x * hm, half.y * hm, half.z * hm};
    const Three x{start.x + d.x, start.y + d.y, start.z + d.z};
    if (pass.p) put(pass.p, i, momentum);
    if (pass.p_start) put(pass.p_start, i, momentum);
    if (pass.half) put(pass.half, i, half);
    if (pass.free) put(pass.free, i, d);
    if (pass.impulse) put(pass.impulse, i, Three{0.0, 0.0, 0.0});
    if (pass.predicted) put(pass.predicted, i, x);
    if (at_build) {
      const Three ref = at(at_build, i);
      tally.beyond_list +=
          !(norm2(Three{x.x - ref.x, x.y - ref.y, x.z - ref.z}) <= pass.list_limit2);
    }
    if (displacement2) {
      const double moved2 = norm2(Three{x.x - start.x, x.y - start.y, x.z - start.z});
      displacement2[i] = moved2;
      tally.largest2 = tally.largest2 < moved2 ? moved2 : tally.largest2;
      if (reach) {
        const double own = 2.0 * __builtin_sqrt(moved2 < floor2 ? floor2 : moved2) + tolerance;
        reach[i] = own;
        reach_limit2[i] = (own - half_tolerance) * (own - half_tolerance);
        if (anchor) {
          const Three a = at(anchor, i);
          const double anchored2 = norm2(Three{start.x - a.x, start.y - a.y, start.z - a.z});
          tally.anchored_largest2 =
              tally.anchored_largest2 < anchored2 ? anchored2 : tally.anchored_largest2;
          moved_from_anchor[i] = __builtin_sqrt(anchored2) + own;
        }
      }
    }
  }
  return tally;
}

void half_kick(double h, const double* p, const double* force, const double* mass, double* half,
               double* free, std::size_t begin, std::size_t end) {
  const double kick = 0.5 * h;
  const double* __restrict momentum = p;
  const double* __restrict f = force;
  const double* __restrict m = mass;
  double* __restrict kicked = half;
  double* __restrict d = free;
  std::size_t i = begin;
  for (; i + w <= end; i += w) {
    const Triples hms = spread(h / load(m + i));
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t e = 3 * i + k * w;
      const Block a = load(momentum + e) + load(f + e) * kick;
      if (kicked) store(kicked + e, a);
      if (d) store(d + e, a * hms.v[k]);
    }
  }
  for (; i < end; ++i) {
    const double hm = h / m[i];
    for (std::size_t k = 0; k < 3; ++k) {
      const double a = momentum[3 * i + k] + f[3 * i + k] * kick;
      if (kicked) kicked[3 * i + k] = a;
      if (d) d[3 * i + k] = a * hm;
    }
  }
}

EndPositionsTally end_positions(const EndPositions& pass, std::size_t begin, std::size_t end) {
  const double h = pass.h;
  const double* __restrict q = pass.q;
  const double* __restrict half = pass.half;
  const double* __restrict impulse = pass.impulse;
  const double* __restrict mass = pass.mass;
  const double* __restrict reach = pass.reach_limit2;
  const double* __restrict at_build = pass.at_build;
  double* __restrict x = pass.x;
  Block largest = broadcast(0.0);
  BlockMask outside_reach = {}, outside_list = {};
  const Block list_limit = broadcast(pass.list_limit2);
  std::size_t i = begin;
  for (; i + w <= end; i += w) {
    const std::size_t o = 3 * i;
    const Triples hms = spread(h / load(mass + i));
    Triples moved, listed;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t e = o + k * w;
      const Block start = load(q + e);
      // A missing impulse is a zero vector, added as it is (+0 turns a -0 sum into +0).
      const Block total_impulse = load(half + e) + (impulse ? load(impulse + e) : broadcast(0.0));
      const Block end_position = start + total_impulse * hms.v[k];
      store(x + e, end_position);
      moved.v[k] = end_position - start;
      if (at_build) listed.v[k] = end_position - load(at_build + e);
    }
    const Block moved2 = norm2s(moved);
    largest = largest < moved2 ? moved2 : largest;
    if (reach) outside_reach += missed(moved2, load(reach + i));
    if (at_build) outside_list += missed(norm2s(listed), list_limit);
  }
  EndPositionsTally tally;
  for (std::size_t l = 0; l < w; ++l) {
    tally.largest2 = tally.largest2 < largest[l] ? largest[l] : tally.largest2;
  }
  tally.beyond_reach = total(outside_reach);
  tally.beyond_list = total(outside_list);
  for (; i < end; ++i) {
    const double hm = h / mass[i];
    const Three start = at(q, i), kicked = at(half, i);
    const Three held = impulse ? at(impulse, i) : Three{0.0, 0.0, 0.0};
    const Three sum{kicked.x + held.x, kicked.y + held.y, kicked.z + held.z};
    const Three end_position{start.x + sum.x * hm, start.y + sum.y * hm, start.z + sum.z * hm};
    put(x, i, end_position);
    const double moved2 =
        norm2(Three{end_position.x - start.x, end_position.y - start.y, end_position.z - start.z});
    tally.largest2 = tally.largest2 < moved2 ? moved2 : tally.largest2;
    if (reach) tally.beyond_reach += !(moved2 <= reach[i]);
    if (at_build) {
      const Three ref = at(at_build, i);
      tally.beyond_list += !(norm2(Three{end_position.x - ref.x, end_position.y - ref.y,
                                         end_position.z - ref.z}) <= pass.list_limit2);
    }
  }
  return tally;
}

void second_kick(double h, const double* half, const double* impulse, const double* force,
                 double* p, std::size_t begin, std::size_t end) {
  const double kick = 0.5 * h;
  const double* __restrict a = half;
  const double* __restrict b = impulse;
  const double* __restrict f = force;
  double* __restrict out = p;
  // A missing impulse is a zero vector, added as it is (+0 turns a -0 sum into +0).
  if (b) {
    for (std::size_t e = 3 * begin; e < 3 * end; ++e) out[e] = (a[e] + b[e]) + f[e] * kick;
  } else {
    for (std::size_t e = 3 * begin; e < 3 * end; ++e) out[e] = (a[e] + 0.0) + f[e] * kick;
  }
}

void velocities(const double* p, const double* mass, double* velocity, std::size_t begin,
                std::size_t end) {
  const double* __restrict momentum = p;
  const double* __restrict m = mass;
  double* __restrict v = velocity;
  std::size_t i = begin;
  for (; i + w <= end; i += w) {
    const Triples inverse = spread(1.0 / load(m + i));
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t e = 3 * i + k * w;
      store(v + e, load(momentum + e) * inverse.v[k]);
    }
  }
  for (; i < end; ++i) {
    const double inverse = 1.0 / m[i];
    for (std::size_t k = 0; k < 3; ++k) v[3 * i + k] = momentum[3 * i + k] * inverse;
  }
}

void kicked_velocities(double h, const double* half, const double* impulse, const double* force,
                       const double* mass, double* velocity, std::size_t begin, std::size_t end) {
  // 64 particles' momenta: 1.5 KB, in L1 between the two loops.
  constexpr std::size_t kBlock = 64;
  double p[3 * kBlock];
  for (std::size_t first = begin; first < end; first += kBlock) {
    const std::size_t count = std::min(kBlock, end - first);
    const std::size_t at = 3 * first;
    second_kick(h, half + at, impulse ? impulse + at : nullptr, force + at, p, 0, count);
    velocities(p, mass + first, velocity + at, 0, count);
  }
}

}  // namespace deli::gvi_passes
