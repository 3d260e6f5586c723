#include "crosscheck/compare.hpp"

#include <algorithm>
#include <cmath>

namespace deli {

Tolerances double_precision_tolerances(bool numeric_virial) {
  return {1e-12, 1e-10, numeric_virial ? 1e-6 : 1e-10, 1e-10};
}

Tolerances single_precision_tolerances() {
  return {1e-5, 1e-3, 1e-3, 1e-3};
}

// Two engines' trajectories start apart by rounding (1e-14 sigma) and separate as
// exp(lambda t) once chaos takes over. deli against LAMMPS (max |dx| after N steps, h =
// 0.005) measured: lj_4000 2.5e-14 (100), 4.9e-13 (300), 1.1e-7 (1000), 1.5 (2000): lambda
// 3.5 per tau; melt 3.6e-14, 2.5e-12, 3.7e-6, 2.6: lambda 4.2; chains_4000_harmonic 2.2e-14,
// 2.7e-13, 2.2e-9, 2e-2: lambda 2.6. The tolerance, set for the first 0.5 tau (100 steps
// of 0.005), grows as exp(5 (t - 0.5)): 5 per tau bounds every rate measured.
double position_tolerance_growth(int steps, double timestep) {
  constexpr double kLyapunov = 5.0, kUngrown = 0.5;
  return std::exp(kLyapunov * std::max(0.0, steps * timestep - kUngrown));
}

double relative_difference(double a, double b) {
  // Below one epsilon a relative difference means nothing (a term that is zero up to
  // rounding): the difference is then measured against 1.
  const double scale = std::max({std::abs(a), std::abs(b), 1.0});
  return std::abs(a - b) / scale;
}

std::vector<Check> compare_evaluations(const EngineEvaluation& deli, const EngineEvaluation& other,
                                       const Tolerances& tolerances,
                                       const std::vector<std::int64_t>& ids) {
  std::vector<Check> checks;
  for (std::size_t t = 0; t < deli.term_names.size(); ++t) {
    const auto at = std::find(other.term_names.begin(), other.term_names.end(), deli.term_names[t]);
    const double theirs =
        at == other.term_names.end() ? 0.0 : other.term_energies[at - other.term_names.begin()];
    checks.push_back({other.engine, "energy " + deli.term_names[t], deli.term_energies[t], theirs,
                      relative_difference(deli.term_energies[t], theirs),
                      tolerances.energy_relative, ""});
  }
  checks.push_back({other.engine, "energy total", deli.potential, other.potential,
                    relative_difference(deli.potential, other.potential),
                    tolerances.energy_relative, ""});
  double worst = 0.0;
  std::size_t worst_atom = 0;
  for (std::size_t i = 0; i < deli.force.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const double d = std::abs(deli.force[i][a] - other.force[i][a]);
      if (d > worst) worst = d, worst_atom = i;
    }
  }
  checks.push_back({other.engine, "max |dF| component", 0, 0, worst, tolerances.force_absolute,
                    deli.force.empty() ? "" : "atom " + std::to_string(ids[worst_atom])});
  if (deli.virial && other.virial) {
    checks.push_back({other.engine, "virial W", *deli.virial, *other.virial,
                      relative_difference(*deli.virial, *other.virial), tolerances.virial_relative,
                      ""});
  }
  return checks;
}

Check compare_positions(const std::string& engine, const std::vector<Vec3>& deli,
                        const std::vector<Vec3>& other, const Tolerances& tolerances,
                        const std::vector<std::int64_t>& ids, int steps) {
  double worst = 0.0;
  std::size_t worst_atom = 0;
  for (std::size_t i = 0; i < deli.size(); ++i) {
    const double d = norm(deli[i] - other[i]);
    if (d > worst) worst = d, worst_atom = i;
  }
  return {engine,
          "max |dx| after " + std::to_string(steps) + " steps",
          0,
          0,
          worst,
          tolerances.position_absolute,
          deli.empty() ? "" : "atom " + std::to_string(ids[worst_atom])};
}

}  // namespace deli
