#pragma once

#include <concepts>

namespace deli {

// What BondForce needs of a bond style: per bond type Params; evaluate() sets
// f_over_r = -phi'(r)/r and the energy and returns false where the potential is undefined
// (a FENE bond stretched past R0: the loop reports the bond); second_derivative() gives
// phi''(r) for the pair Hessian.
template <class E>
concept BondEvaluator = std::default_initializable<typename E::Params> &&
    requires(const typename E::Params& p, double r2, double& f_over_r, double& energy) {
  { E::evaluate(p, r2, f_over_r, energy) } -> std::same_as<bool>;
  { E::second_derivative(p, r2) } -> std::convertible_to<double>;
};

}  // namespace deli
