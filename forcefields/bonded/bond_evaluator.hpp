#pragma once

#include <concepts>

namespace deli {

// What BondForce needs of a bond style: per bond type Params; evaluate<kEnergy>() sets
// f_over_r = -phi'(r)/r, and the energy with kEnergy, and returns false where the potential
// is undefined (a FENE bond stretched past R0: the loop reports the bond); second_derivative()
// gives phi''(r) for the pair Hessian. Untallied steps ask for no energy: FENE's logarithm,
// which the compiler must keep (it may set errno), was most of a FENE melt's bond time.
template <class E>
concept BondEvaluator = std::default_initializable<typename E::Params> &&
    requires(const typename E::Params& p, double r2, double& f_over_r, double& energy) {
  { E::template evaluate<true>(p, r2, f_over_r, energy) } -> std::same_as<bool>;
  { E::template evaluate<false>(p, r2, f_over_r, energy) } -> std::same_as<bool>;
  { E::second_derivative(p, r2) } -> std::convertible_to<double>;
};

}  // namespace deli
