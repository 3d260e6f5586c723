#pragma once

#include <cmath>

#include "pair/pair_evaluator.hpp"
#include "pair/vector_pair_loop.hpp"

namespace deli {

// 12-6 Lennard-Jones, truncated at a cutoff (the pair loop shifts it to zero energy there
// when asked). WCA is this with cutoff 2^(1/6) sigma, shifted.
struct LennardJones {
  struct Params {
    double lj1 = 0, lj2 = 0;  // 48 eps sig^12, 24 eps sig^6: force
    double lj3 = 0, lj4 = 0;  // 4 eps sig^12, 4 eps sig^6: energy
    double cutoff2 = 0;
    double energy_shift = 0;  // the pair loop's
  };

  static Params make(double epsilon, double sigma, double cutoff) {
    Params p;
    const double s6 = std::pow(sigma, 6);
    p.lj1 = 48.0 * epsilon * s6 * s6;
    p.lj2 = 24.0 * epsilon * s6;
    p.lj3 = 4.0 * epsilon * s6 * s6;
    p.lj4 = 4.0 * epsilon * s6;
    p.cutoff2 = cutoff * cutoff;
    return p;
  }

  static double cutoff_energy(const Params& p) {
    const double r6inv = 1.0 / (p.cutoff2 * p.cutoff2 * p.cutoff2);
    return r6inv * (p.lj3 * r6inv - p.lj4);
  }

  // phi''(r) for r2 < cutoff2.
  static double second_derivative(const Params& p, double r2) {
    const double r2inv = 1.0 / r2;
    const double r6inv = r2inv * r2inv * r2inv;
    return r6inv * (13.0 * p.lj1 * r6inv - 7.0 * p.lj2) * r2inv;
  }

  // For r2 < cutoff2: force divided by r (so F_i = d_ij * f_over_r) and the unshifted
  // energy.
  static void evaluate(const Params& p, double r2, double& f_over_r, double& energy) {
    const double r2inv = 1.0 / r2;
    const double r6inv = r2inv * r2inv * r2inv;
    f_over_r = r6inv * (p.lj1 * r6inv - p.lj2) * r2inv;
    energy = r6inv * (p.lj3 * r6inv - p.lj4);
  }

  // PairForce's loop eight pairs at a time (lennard_jones_vector.cpp, under DELI_NATIVE:
  // one AVX-512 vector on a CPU that has it, two AVX2 vectors of four on one that has AVX2). Each
  // pair's f/r and energy are evaluate()'s bits, and the energy and virial are summed in the scalar
  // loop's order (the same bits); a particle's own force is summed by lane, so forces differ from
  // the scalar loop's in the last bits (the same on every run, and in every build: see
  // lane_order_loop).
  static bool vector_loop_built();
  static double vector_loop(const Params& p, const VectorPairChunk& chunk, bool tally,
                            SymTensor& virial);
  // vector_loop's sums one pair at a time, in its order: the same bits in any build (AVX-512,
  // AVX2 or the portable build's vector_loop, and PairForce's loop for one type wherever it
  // runs).
  static double lane_order_loop(const Params& p, const VectorPairChunk& chunk, bool tally,
                                SymTensor& virial);
  // The shadow energy's curvature sum by vector (eight pairs at a time with AVX-512, four with
  // AVX2, where built; false otherwise, and PairForce sums it pair by pair).
  static bool curvature_loop_built();
  static double curvature_loop(const Params& p, const CurvatureChunk& chunk);
};
static_assert(PairEvaluator<LennardJones>);
static_assert(VectorPairEvaluator<LennardJones>);
static_assert(VectorCurvatureEvaluator<LennardJones>);

}  // namespace deli
