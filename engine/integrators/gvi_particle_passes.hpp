#pragma once

#include <cstddef>

namespace deli::gvi_passes {

// GVI's passes over the particles [begin, end) of arrays of xyz triples (3 doubles a particle,
// the layout of std::vector<Vec3>), eight particles at a time in vectors (four on a CPU with
// AVX2 and not AVX-512: lane_vectors::kQuarterLanes). Each number is made
// by the operations, in the order, of the scalar expressions written beside each function
// (no fused multiply-add: -ffp-contract=off), so the results are bit for bit those of a loop
// over Vec3. Their file alone is built for the build machine's CPU (DELI_NATIVE), so it
// includes no header with inline code that the rest of the engine would share.

// The start of a Verlet step, per particle i with m = mass[i]:
//   q = position; momentum = velocity * m; p = momentum; p_start = momentum;
//   half = momentum + force * (0.5 h); free = half * (h / m); impulse = 0;
//   predicted = position + free; displacement2 = |predicted - q|^2;
// and the count of particles whose predicted position is not within the neighbour list's
// reach, !(|predicted - at_build|^2 <= list_limit2), and the largest displacement2 (from 0, a
// NaN passed over, as ordered_max takes it; 0 unless displacement2 is written). Null outputs
// are not written; a null at_build counts none.
// Given `reach` (with displacement2), also the particles' reaches for the candidate rows
// (Gvi::collect_by_particle_reach's, from a floor given beforehand) and, given `anchor`, their
// displacements from the short list's anchors plus those reaches (NearbyRows::collect's):
//   s = displacement2 < reach_floor2 ? reach_floor2 : displacement2;
//   reach = 2 * sqrt(s) + gap_tolerance; reach_limit2 = (reach - gap_tolerance / 2)^2;
//   anchored2 = |q - anchor|^2; moved = sqrt(anchored2) + reach;
// with the largest anchored2 (from 0, a NaN passed over).
struct StepStart {
  double h = 0.0;
  const double* position = nullptr;
  const double* velocity = nullptr;
  const double* mass = nullptr;  // one a particle
  const double* force = nullptr;
  const double* at_build = nullptr;
  double list_limit2 = 0.0;
  double* q = nullptr;
  double* p = nullptr;
  double* p_start = nullptr;
  double* half = nullptr;
  double* free = nullptr;
  double* impulse = nullptr;
  double* predicted = nullptr;
  double* displacement2 = nullptr;  // one a particle; read only with predicted
  double reach_floor2 = 0.0;
  double gap_tolerance = 0.0;
  double* reach = nullptr;         // one a particle; read only with displacement2
  double* reach_limit2 = nullptr;  // one a particle; written with reach
  const double* anchor = nullptr;  // read only with reach
  double* moved = nullptr;         // one a particle; written with anchor
};
struct StepStartTally {
  std::size_t beyond_list = 0;
  double largest2 = 0.0;
  double anchored_largest2 = 0.0;
};
StepStartTally step_start(const StepStart& pass, std::size_t begin, std::size_t end);

// The half kick and free step of momenta p, per particle i with m = mass[i]:
//   half = p + force * (0.5 h); free = half * (h / m);
// (a null output is not written).
void half_kick(double h, const double* p, const double* force, const double* mass, double* half,
               double* free, std::size_t begin, std::size_t end);

// The end positions, per particle i with m = mass[i] (a null impulse reads as zeros):
//   x = q + (half + impulse) * (h / m); moved2 = |x - q|^2;
// with the largest moved2 (NaN passed over, as std::max(largest, moved2) from 0 does), the
// count of !(moved2 <= reach_limit2[i]) (none with a null reach_limit2) and the count of
// !(|x - at_build|^2 <= list_limit2) (none with a null at_build).
struct EndPositions {
  double h = 0.0;
  const double* q = nullptr;
  const double* half = nullptr;
  const double* impulse = nullptr;
  const double* mass = nullptr;
  const double* reach_limit2 = nullptr;  // one a particle
  const double* at_build = nullptr;
  double list_limit2 = 0.0;
  double* x = nullptr;
};
struct EndPositionsTally {
  double largest2 = 0.0;
  std::size_t beyond_reach = 0;
  std::size_t beyond_list = 0;
};
EndPositionsTally end_positions(const EndPositions& pass, std::size_t begin, std::size_t end);

// The second half kick of the momenta: p = (half + impulse) + force * (0.5 h) per number (a
// null impulse reads as zeros).
void second_kick(double h, const double* half, const double* impulse, const double* force,
                 double* p, std::size_t begin, std::size_t end);

// The velocities of the momenta: velocity = p * (1 / mass[i]) per particle i.
void velocities(const double* p, const double* mass, double* velocity, std::size_t begin,
                std::size_t end);

// The velocities of second_kick's momenta, the numbers of second_kick then velocities, the
// momenta made a block of particles at a time on the stack and not stored (the momentum update
// where nothing reads them after the velocities).
void kicked_velocities(double h, const double* half, const double* impulse, const double* force,
                       const double* mass, double* velocity, std::size_t begin, std::size_t end);

}  // namespace deli::gvi_passes
