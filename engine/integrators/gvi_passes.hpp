#pragma once

#include <cstddef>

namespace deli::gvi_passes {

// The per-particle passes of a Verlet GVI step over particles [begin, end), on arrays of three
// doubles a particle (as Vec3 lays them out) and one mass a particle. Each number is made by
// the operations Vec3's operators make in gvi.cpp, in the same order, so the results are the
// same bits whether a pass runs here or there (no fused multiply-add: -ffp-contract=off; IEEE
// division and comparisons are the same in vector form). Their file alone is built for the
// build machine's CPU (DELI_NATIVE), as the rod passes are: it includes no Eigen and no
// templates the rest of the engine shares.

// The start of a step: q = x, p = v m, and the free step's end x + (p + f (h/2)) (h / m),
// stored into `predicted` unless null. Returns how many of those ends lie beyond the
// neighbour list's reach: |end - built|^2 > limit2 (NeighborList::keeps_valid; built null:
// none counted).
std::size_t start(std::size_t begin, std::size_t end, double h, const double* x, const double* v,
                  const double* mass, const double* f, double* q, double* p, double* predicted,
                  const double* built, double limit2);

// The first half kick and the free step: half = p + f (h/2), free = half (h / m).
void half_kick(std::size_t begin, std::size_t end, double h, const double* p, const double* f,
               const double* mass, double* half, double* free);

// The end positions x = q + (half + impulse) (h / m) (impulse null: a zero impulse) and, over
// |x - q|^2: its maximum from `largest` (std::max), how many exceed reach2[i] (reach2 null:
// none counted) and how many ends lie beyond the neighbour list's reach (as start()).
struct EndPositions {
  double largest = 0.0;
  std::size_t beyond_reach = 0, beyond_list = 0;
};
EndPositions end_positions(std::size_t begin, std::size_t end, double h, const double* q,
                           const double* half, const double* impulse, const double* mass, double* x,
                           double largest, const double* reach2, const double* built,
                           double limit2);

// The second half kick: p = (half + impulse) + f (h/2) (impulse null: a zero impulse).
void kick(std::size_t begin, std::size_t end, double h, const double* half, const double* impulse,
          const double* f, double* p);

// v = p (1 / m).
void velocities(std::size_t begin, std::size_t end, const double* p, const double* mass, double* v);

}  // namespace deli::gvi_passes
