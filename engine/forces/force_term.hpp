#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace deli {

struct System;
class NeighborList;

struct PairHessian {
  std::int32_t a, b;
  Eigen::Matrix3d block;
};

// Pair Hessian blocks kept in the pieces the threads made them in, read as one sequence: the
// first piece's blocks, then the next piece's. Joined into one vector, the blocks of the
// default input's second thread (some 1200 a call, 96 KB) were copied by the calling thread
// at every shadow-H reflection while the other thread waited. Pieces past the used ones keep
// their storage for the next call.
struct PairHessianPieces {
  std::vector<std::vector<PairHessian>> pieces;
  std::size_t used = 0;

  // No blocks; the pieces' storage kept.
  void clear() {
    for (std::size_t k = 0; k < used; ++k) pieces[k].clear();
    used = 0;
  }
  // The last piece in use (a first one if none), for blocks that follow every block so far.
  std::vector<PairHessian>& last() {
    if (used == 0) return add();
    return pieces[used - 1];
  }
  // A new, empty last piece. It moves the pieces (not their blocks): take references to
  // pieces only once every piece is added.
  std::vector<PairHessian>& add() {
    if (pieces.size() == used) pieces.emplace_back();
    pieces[used].clear();
    return pieces[used++];
  }
};

// The Hessian block of phi(|d|) for d = x_a - x_b, from phi'' and f_over_r = -phi'(r)/r:
// phi'' d^ d^T - f_over_r (I - d^ d^T).
inline Eigen::Matrix3d pair_hessian_block(const Vec3& d, double r2, double f_over_r,
                                          double second_derivative) {
  const Eigen::Vector3d u = Eigen::Vector3d(d.x, d.y, d.z) / std::sqrt(r2);
  const Eigen::Matrix3d uu = u * u.transpose();
  return second_derivative * uu - f_over_r * (Eigen::Matrix3d::Identity() - uu);
}

// pair_hessian_block's six distinct elements, each by its operations (the same bits; the block
// is symmetric bit for bit, u_a u_b being u_b u_a): the form a loop over many pairs runs in
// vectors (PairForce's masked blocks).
struct PairHessianUpper {
  double xx, xy, xz, yy, yz, zz;
};
inline PairHessianUpper pair_hessian_upper(double dx, double dy, double dz, double r2,
                                           double f_over_r, double second_derivative) {
  const double r = std::sqrt(r2);
  const double ux = dx / r, uy = dy / r, uz = dz / r;
  auto element = [&](double uu, double identity) {
    return second_derivative * uu - f_over_r * (identity - uu);
  };
  return {element(ux * ux, 1.0), element(ux * uy, 0.0), element(ux * uz, 0.0),
          element(uy * uy, 1.0), element(uy * uz, 0.0), element(uz * uz, 1.0)};
}

// One term of the potential energy (all pairs of one style, all bonds of one style...).
// compute() adds its forces and, when `tally`, its virial, and returns its energy (0 when
// not `tally`: most steps need forces only). One virtual call per term per step, never per
// pair.
class ForceTerm {
 public:
  virtual ~ForceTerm() = default;
  virtual std::string name() const = 0;
  // Largest interaction distance that must come from the neighbour list (0: none).
  virtual double neighbor_cutoff() const { return 0.0; }
  virtual double compute(const System& system, const NeighborList& neighbors,
                         std::vector<Vec3>& force, SymTensor& virial, bool tally) const = 0;
  // compute() onto a force array whose contents it replaces (the force field's first term):
  // this default zeroes the array, then adds. A term whose loop writes every particle's force
  // once (the pair styles' vector loop) writes it in place of the zeroing pass, in which one
  // thread zeroed lines the other thread had just written.
  virtual double compute_overwriting(const System& system, const NeighborList& neighbors,
                                     std::vector<Vec3>& force, SymTensor& virial, bool tally) const;

  // The Hessian of a pairwise term is a sum of blocks: for a pair (a, b) with block B,
  // (H v)_a += B (v_a - v_b) and (H v)_b += B (v_b - v_a). Appends the blocks of the pairs
  // touching a particle with mask set (every pair when the mask is empty). Returns false
  // for terms whose Hessian is not pairwise (angles): shadow energies are then unavailable.
  virtual bool pair_hessians(const System&, const NeighborList&, const std::vector<char>& /*mask*/,
                             std::vector<PairHessian>& /*out*/) const {
    return false;
  }
  // The same blocks in the same order, appended to `out` as pieces: a term that makes its
  // blocks in chunks on several threads keeps each chunk's as a piece; this default appends
  // pair_hessians' to the last piece.
  virtual bool pair_hessian_pieces(const System& system, const NeighborList& neighbors,
                                   const std::vector<char>& mask, PairHessianPieces& out) const {
    return pair_hessians(system, neighbors, mask, out.last());
  }
  // Adds v^T H v = sum over blocks of (v_a - v_b)^T B (v_a - v_b) to `sum`, in
  // pair_hessians' order. This default goes through pair_hessians (the same sum as from its
  // blocks, bit for bit); pair styles override it with each block's term in closed form,
  // without building the blocks (the blocks' sum to round-off).
  virtual bool pair_curvature(const System& system, const NeighborList& neighbors,
                              const std::vector<Vec3>& velocity, double& sum) const;
};

// (v_a - v_b)^T B (v_a - v_b) for one block.
inline double block_curvature(const Eigen::Matrix3d& block, const Vec3& va, const Vec3& vb) {
  const Vec3 dv = va - vb;
  const Eigen::Vector3d v(dv.x, dv.y, dv.z);
  return v.dot(block * v);
}

}  // namespace deli
