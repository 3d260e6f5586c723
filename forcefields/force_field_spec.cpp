#include "force_field_spec.hpp"

#include <algorithm>

#include "external/gravity.hpp"
#include "external/radial_potentials.hpp"
#include "system/system.hpp"

namespace deli {

double PairSpec::max_cutoff() const {
  double cutoff = 0.0;
  const int n = coefficients.type_count();
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) cutoff = std::max(cutoff, coefficients.at(a, b).cutoff);
  }
  return cutoff;
}

namespace {
std::vector<ScaledPair> scaled_special_pairs(const System& system,
                                             const std::array<double, 3>& factors) {
  std::vector<ScaledPair> scaled;
  const SpecialPairs special = find_special_pairs(system.topology, system.particles.size());
  for (int s = 0; s < 3; ++s) {
    if (factors[s] == 0.0 || factors[s] == 1.0) continue;
    for (const auto& [i, j] : special.by_separation[s]) scaled.push_back({i, j, factors[s]});
  }
  return scaled;
}
}  // namespace

std::unique_ptr<ForceField> build_force_field(const ForceFieldSpec& spec, const System& system) {
  auto ff = std::make_unique<ForceField>();
  ff->special_lj = spec.special_lj;
  if (spec.pair) {
    ff->add(spec.pair->style->make_term(spec.pair->coefficients, spec.pair->shift,
                                        spec.pair->max_cutoff(),
                                        scaled_special_pairs(system, spec.special_lj)));
  }
  if (spec.bond) ff->add(spec.bond->style->make_term(spec.bond->by_type));
  if (spec.angle) ff->add(spec.angle->style->make_term(spec.angle->by_type));
  if (spec.gravity) ff->add(std::make_unique<Gravity>(*spec.gravity));
  for (const ForceFieldSpec::Radial& r : spec.radial) {
    ff->add(std::make_unique<RadialPotential>(r.inverse_square
                                                  ? RadialPotential::Kind::inverse_square
                                                  : RadialPotential::Kind::polynomial,
                                              r.center, r.coefficients));
  }
  return ff;
}

}  // namespace deli
