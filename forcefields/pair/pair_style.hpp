#pragma once

#include <memory>
#include <string>
#include <vector>

#include "forces/force_term.hpp"
#include "pair/pair_coefficients.hpp"
#include "pair/pair_force.hpp"
#include "style_coefficient.hpp"

namespace deli {

// A pair style, described once, in the style's own file: how its coefficients are read
// and mixed, the term deli computes, and how OpenMM and LAMMPS express the same potential
// (as strings: the forcefields layer stays free of their headers).
struct PairStyle {
  std::string name;  // the input's style
  std::vector<StyleCoefficient> coefficients;
  std::vector<MixRule> mixing;  // per coefficient
  std::string data_form;        // a data-file row's form, for errors: "lj/cut coefficients are ..."
  // The cutoff the style fixes from the coefficients (WCA: 2^(1/6) sigma), or nullptr:
  // the input's global cutoff, or a pair's own.
  double (*fixed_cutoff)(const std::vector<double>& values);
  bool always_shifted;  // else shifted to zero at the cutoff only when the input asks
  // The unshifted energy and |dE/dr| at r: the shift constant OpenMM is given, and
  // validate's estimate of the jump at the cutoff.
  double (*energy)(const std::vector<double>& values, double r);
  double (*force)(const std::vector<double>& values, double r);
  std::unique_ptr<ForceTerm> (*make_term)(const PairCoefficients& coefficients, bool shift,
                                          double max_cutoff, std::vector<ScaledPair> scaled);
  // The unshifted energy as an OpenMM custom-force expression in r and the coefficients'
  // names; empty: not available in OpenMM.
  std::string openmm_energy;
  // LAMMPS' pair_style (pair_coeff a b values... cutoff; pair_modify shift yes|no); empty:
  // not available in LAMMPS.
  std::string lammps_style;
};

// The registered pair styles, in the order the input's errors list them.
const std::vector<const PairStyle*>& pair_styles();
// nullptr when no pair style has that name.
const PairStyle* find_pair_style(const std::string& name);

}  // namespace deli
