#include "force_field_spec.hpp"

#include <algorithm>

#include "bonded/term_sum.hpp"
#include "external/gravity.hpp"
#include "external/radial_potentials.hpp"
#include "forces/special_bonds.hpp"
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
  for (const ExcludedSpecialPair& p : excluded_special_pairs(special, factors)) {
    if (p.scaled()) scaled.push_back({p.i, p.j, p.factor});
  }
  return scaled;
}
// One style's term, or, when types differ in style, one term per style (each computing the
// bonds of its own types) summed under the kind's name, as LAMMPS' hybrid styles do.
std::unique_ptr<ForceTerm> bonded_term(const BondedSpec& spec, const std::string& name) {
  const std::vector<const BondedStyle*> styles = spec.styles();
  if (styles.size() == 1) return styles.front()->make_term(spec.by_type, {});
  auto sum = std::make_unique<TermSum>(name);
  for (const BondedStyle* style : styles) {
    std::vector<std::vector<double>> by_type = spec.by_type;
    std::vector<char> own(by_type.size(), 0);
    for (std::size_t t = 0; t < by_type.size(); ++t) {
      own[t] = spec.style_by_type[t] == style;
      if (!own[t]) by_type[t].assign(style->coefficients.size(), 0.0);
    }
    sum->add(style->make_term(by_type, own));
  }
  return sum;
}

}  // namespace

std::vector<const BondedStyle*> BondedSpec::styles() const {
  std::vector<const BondedStyle*> distinct;
  for (const BondedStyle* s : style_by_type) {
    if (std::find(distinct.begin(), distinct.end(), s) == distinct.end()) distinct.push_back(s);
  }
  if (distinct.empty()) distinct.push_back(style);  // a kind with no types
  return distinct;
}

std::unique_ptr<ForceField> build_force_field(const ForceFieldSpec& spec, const System& system) {
  auto ff = std::make_unique<ForceField>();
  ff->special_lj = spec.special_lj;
  if (spec.pair) {
    ff->add(spec.pair->style->make_term(spec.pair->coefficients, spec.pair->shift,
                                        spec.pair->max_cutoff(),
                                        scaled_special_pairs(system, spec.special_lj)));
  }
  if (spec.bond) ff->add(bonded_term(*spec.bond, "bond"));
  if (spec.angle) ff->add(bonded_term(*spec.angle, "angle"));
  if (spec.dihedral) ff->add(bonded_term(*spec.dihedral, "dihedral"));
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
