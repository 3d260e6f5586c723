#pragma once

#include <optional>
#include <string>
#include <vector>

namespace deli {

enum class Mixing { arithmetic, geometric };

// epsilon, sigma and cutoff for one pair of types.
struct PairCoefficient {
  double epsilon = 0, sigma = 0, cutoff = 0;
};

// Per-type-pair coefficients as given by the user, completed by mixing: a pair not given
// takes epsilon = sqrt(eps_i eps_j) and sigma, cutoff mixed from the like pairs
// (arithmetic: Lorentz-Berthelot; geometric), as LAMMPS' pair_modify mix does.
class PairCoefficients {
 public:
  PairCoefficients(int type_count, double global_cutoff);

  int type_count() const { return type_count_; }
  void set(int type_a, int type_b, double epsilon, double sigma, std::optional<double> cutoff);
  bool is_set(int type_a, int type_b) const;
  // Fills unset unlike pairs; returns the like pairs that are missing (0-based types).
  std::vector<int> resolve(Mixing mixing);
  const PairCoefficient& at(int type_a, int type_b) const {
    return table_[type_a * type_count_ + type_b];
  }

 private:
  int type_count_;
  double global_cutoff_;
  std::vector<PairCoefficient> table_;
  std::vector<bool> given_;
};

}  // namespace deli
