#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "forces/force_term.hpp"

namespace deli {

// Energies of each term from one evaluation, in the order the terms were added.
struct ForceEvaluation {
  std::vector<std::string> names;
  std::vector<double> energies;
  double potential = 0.0;
  bool tallied = false;  // energies and virial filled in (else forces only)
  SymTensor virial;      // sum over interactions of r_ij (x) f_ij
};

// The potential: a list of terms sharing one neighbour list.
class ForceField {
 public:
  void add(std::unique_ptr<ForceTerm> term);
  const std::vector<std::unique_ptr<ForceTerm>>& terms() const { return terms_; }
  double neighbor_cutoff() const;

  // Overwrites `force` with the total force; energies and virial only when `tally`.
  ForceEvaluation compute(const System& system, const NeighborList& neighbors,
                          std::vector<Vec3>& force, bool tally = true) const;

  // Pair Hessian blocks of every term touching a masked particle (all with an empty mask);
  // false when some term has no pairwise Hessian (angles).
  bool pair_hessians(const System& system, const NeighborList& neighbors,
                     const std::vector<char>& mask, std::vector<PairHessian>& out) const;
  // The same blocks as pieces (ForceTerm::pair_hessian_pieces), appended to `out`.
  bool pair_hessian_pieces(const System& system, const NeighborList& neighbors,
                           const std::vector<char>& mask, PairHessianPieces& out) const;
  // v^T H v over every term (false as pair_hessians), without storing the blocks.
  bool pair_curvature(const System& system, const NeighborList& neighbors,
                      const std::vector<Vec3>& velocity, double& sum) const;

  // LAMMPS special_bonds lj factors for 1-2, 1-3, 1-4 neighbours.
  std::array<double, 3> special_lj{0.0, 0.0, 0.0};
  // Pair loops in the neighbour list's cell order ([neighbor] cell_order; an input has it
  // on where there is a pair loop): faster on a liquid whose particle order is scrambled;
  // sums in another order (round-off).
  bool cell_order = false;

 private:
  std::vector<std::unique_ptr<ForceTerm>> terms_;
};

}  // namespace deli
