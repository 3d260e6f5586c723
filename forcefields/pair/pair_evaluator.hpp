#pragma once

#include <concepts>

namespace deli {

// What PairForce needs of a pair style (HOOMD's evaluator contract): per type pair Params
// holding the squared cutoff; for r2 < cutoff2, evaluate() sets f_over_r = -phi'(r)/r (so
// F_i = d_ij f_over_r) and the energy, and second_derivative() gives phi''(r) for the
// pair Hessian (shadow energies, reflections). Neighbour list, images, exclusions, scaled
// special pairs, energy and virial tallies are the loop's.
template <class E>
concept PairEvaluator = std::default_initializable<typename E::Params> &&
    requires(const typename E::Params& p, double r2, double& f_over_r, double& energy) {
  { p.cutoff2 } -> std::convertible_to<double>;
  { E::evaluate(p, r2, f_over_r, energy) } -> std::same_as<void>;
  { E::second_derivative(p, r2) } -> std::convertible_to<double>;
};

}  // namespace deli
