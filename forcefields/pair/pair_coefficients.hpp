#pragma once

#include <optional>
#include <string>
#include <vector>

namespace deli {

enum class Mixing { arithmetic, geometric };

// How an unlike pair's coefficient follows from the like pairs': always their geometric
// mean (LJ's epsilon), or by the input's mixing rule (LJ's sigma; the cutoff always).
enum class MixRule { geometric, chosen };

// One pair of types: the style's coefficients (its registration's order) and the cutoff.
struct PairCoefficient {
  std::vector<double> values;
  double cutoff = 0;
};

// Per-type-pair coefficients as given by the user, completed by mixing (as LAMMPS'
// pair_modify mix does): arithmetic is Lorentz-Berthelot for LJ.
class PairCoefficients {
 public:
  PairCoefficients(int type_count, double global_cutoff);

  int type_count() const { return type_count_; }
  void set(int type_a, int type_b, std::vector<double> values, std::optional<double> cutoff);
  bool is_set(int type_a, int type_b) const;
  // Fills unset unlike pairs, coefficient k by rules[k]; returns the like pairs that are
  // missing (0-based types).
  std::vector<int> resolve(Mixing mixing, const std::vector<MixRule>& rules);
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
