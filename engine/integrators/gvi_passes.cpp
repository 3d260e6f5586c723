#include "integrators/gvi_passes.hpp"

namespace deli::gvi_passes {

// __restrict: the arrays never overlap, so the loops vectorise without runtime alias checks.

namespace {
// start in blocks, as end_positions_in_blocks.
template <bool keep, bool with_list>
std::size_t start_in_blocks(std::size_t begin, std::size_t end, double h,
                            const double* __restrict x, const double* __restrict v,
                            const double* __restrict mass, const double* __restrict f,
                            double* __restrict q, double* __restrict p,
                            double* __restrict predicted, const double* __restrict built,
                            double limit2) {
  constexpr std::size_t block = 256;
  double listed2[block];
  const double half_step = 0.5 * h;
  std::size_t beyond = 0;
  for (std::size_t first = begin; first < end; first += block) {
    const std::size_t count = end - first < block ? end - first : block;
    for (std::size_t b = 0; b < count; ++b) {
      const std::size_t i = first + b;
      const double m = mass[i];
      const double weight = h / m;
      double from_build[3];
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t k = 3 * i + c;
        q[k] = x[k];
        const double momentum = v[k] * m;
        p[k] = momentum;
        const double at = x[k] + (momentum + f[k] * half_step) * weight;
        if constexpr (keep) predicted[k] = at;
        if constexpr (with_list) from_build[c] = at - built[k];
      }
      if constexpr (with_list) {
        listed2[b] = from_build[0] * from_build[0] + from_build[1] * from_build[1] +
                     from_build[2] * from_build[2];
      }
    }
    if constexpr (with_list) {
      for (std::size_t b = 0; b < count; ++b) beyond += !(listed2[b] <= limit2);
    }
  }
  return beyond;
}
}  // namespace

std::size_t start(std::size_t begin, std::size_t end, double h, const double* x, const double* v,
                  const double* mass, const double* f, double* q, double* p, double* predicted,
                  const double* built, double limit2) {
  if (predicted) {
    return built ? start_in_blocks<true, true>(begin, end, h, x, v, mass, f, q, p, predicted, built,
                                               limit2)
                 : start_in_blocks<true, false>(begin, end, h, x, v, mass, f, q, p, predicted,
                                                built, limit2);
  }
  return built ? start_in_blocks<false, true>(begin, end, h, x, v, mass, f, q, p, predicted, built,
                                              limit2)
               : start_in_blocks<false, false>(begin, end, h, x, v, mass, f, q, p, predicted, built,
                                               limit2);
}

void half_kick(std::size_t begin, std::size_t end, double h, const double* __restrict p,
               const double* __restrict f, const double* __restrict mass, double* __restrict half,
               double* __restrict free) {
  const double half_step = 0.5 * h;
  for (std::size_t i = begin; i < end; ++i) {
    const double weight = h / mass[i];
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t k = 3 * i + c;
      const double kicked = p[k] + f[k] * half_step;
      half[k] = kicked;
      free[k] = kicked * weight;
    }
  }
}

namespace {
// end_positions in blocks: the positions and squared distances first (a loop without branches,
// which vectorises), then the maximum and counts over the block.
template <bool with_impulse, bool with_reach, bool with_list>
EndPositions end_positions_in_blocks(std::size_t begin, std::size_t end, double h,
                                     const double* __restrict q, const double* __restrict half,
                                     const double* __restrict impulse,
                                     const double* __restrict mass, double* __restrict x,
                                     double largest, const double* __restrict reach2,
                                     const double* __restrict built, double limit2) {
  constexpr std::size_t block = 256;
  double moved2[block], listed2[block];
  EndPositions out;
  for (std::size_t first = begin; first < end; first += block) {
    const std::size_t count = end - first < block ? end - first : block;
    for (std::size_t b = 0; b < count; ++b) {
      const std::size_t i = first + b;
      const double weight = h / mass[i];
      double moved[3], from_build[3];
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t k = 3 * i + c;
        const double j = with_impulse ? impulse[k] : 0.0;
        const double at = q[k] + (half[k] + j) * weight;
        x[k] = at;
        moved[c] = at - q[k];
        if constexpr (with_list) from_build[c] = at - built[k];
      }
      moved2[b] = moved[0] * moved[0] + moved[1] * moved[1] + moved[2] * moved[2];
      if constexpr (with_list) {
        listed2[b] = from_build[0] * from_build[0] + from_build[1] * from_build[1] +
                     from_build[2] * from_build[2];
      }
    }
    for (std::size_t b = 0; b < count; ++b) largest = largest < moved2[b] ? moved2[b] : largest;
    if constexpr (with_reach) {
      for (std::size_t b = 0; b < count; ++b) out.beyond_reach += !(moved2[b] <= reach2[first + b]);
    }
    if constexpr (with_list) {
      for (std::size_t b = 0; b < count; ++b) out.beyond_list += !(listed2[b] <= limit2);
    }
  }
  out.largest = largest;
  return out;
}
}  // namespace

EndPositions end_positions(std::size_t begin, std::size_t end, double h, const double* q,
                           const double* half, const double* impulse, const double* mass, double* x,
                           double largest, const double* reach2, const double* built,
                           double limit2) {
  const auto run = [&]<bool with_impulse, bool with_reach, bool with_list>() {
    return end_positions_in_blocks<with_impulse, with_reach, with_list>(
        begin, end, h, q, half, impulse, mass, x, largest, reach2, built, limit2);
  };
  const int kind = (impulse ? 4 : 0) + (reach2 ? 2 : 0) + (built ? 1 : 0);
  switch (kind) {
    case 0:
      return run.template operator()<false, false, false>();
    case 1:
      return run.template operator()<false, false, true>();
    case 2:
      return run.template operator()<false, true, false>();
    case 3:
      return run.template operator()<false, true, true>();
    case 4:
      return run.template operator()<true, false, false>();
    case 5:
      return run.template operator()<true, false, true>();
    case 6:
      return run.template operator()<true, true, false>();
    default:
      return run.template operator()<true, true, true>();
  }
}

void kick(std::size_t begin, std::size_t end, double h, const double* __restrict half,
          const double* __restrict impulse, const double* __restrict f, double* __restrict p) {
  const double half_step = 0.5 * h;
  if (impulse) {
    for (std::size_t k = 3 * begin; k < 3 * end; ++k)
      p[k] = (half[k] + impulse[k]) + f[k] * half_step;
  } else {
    for (std::size_t k = 3 * begin; k < 3 * end; ++k) p[k] = (half[k] + 0.0) + f[k] * half_step;
  }
}

void velocities(std::size_t begin, std::size_t end, const double* __restrict p,
                const double* __restrict mass, double* __restrict v) {
  for (std::size_t i = begin; i < end; ++i) {
    const double inverse = 1.0 / mass[i];
    for (std::size_t c = 0; c < 3; ++c) v[3 * i + c] = p[3 * i + c] * inverse;
  }
}

}  // namespace deli::gvi_passes
