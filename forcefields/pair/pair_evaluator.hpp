#pragma once

#include <concepts>

namespace deli {

// What PairForce needs of a pair style (HOOMD's evaluator contract): per type pair Params
// holding the squared cutoff and the energy shift the loop fills in; for
// r2 < cutoff2, evaluate() sets f_over_r = -phi'(r)/r (so F_i = d_ij f_over_r) and the
// unshifted energy phi(r), second_derivative() gives phi''(r) for the pair Hessian (shadow
// energies, reflections), and cutoff_energy() phi at the cutoff. Neighbour list, images,
// exclusions, scaled special pairs, the energy shift, energy and virial tallies are the
// loop's.
template <class E>
concept PairEvaluator = std::default_initializable<typename E::Params> &&
    requires(typename E::Params& p, double r2, double& f_over_r, double& energy) {
  { p.cutoff2 } -> std::convertible_to<double>;
  {p.energy_shift = 0.0};
  { E::evaluate(p, r2, f_over_r, energy) } -> std::same_as<void>;
  { E::second_derivative(p, r2) } -> std::convertible_to<double>;
  { E::cutoff_energy(p) } -> std::convertible_to<double>;
};

}  // namespace deli
