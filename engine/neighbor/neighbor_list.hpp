#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/vec3.hpp"
#include "system/box.hpp"

namespace deli {

// Half Verlet list (each pair once, under either of its particles) built through a cell
// list, with pairs whose minimum-image distance is below cutoff + skin. Pairs in
// `excluded` never appear. It stays valid until some particle has moved more than skin / 2
// since the build: then no pair can have closed from beyond cutoff + skin to within the
// cutoff. Neighbours of each particle are in ascending index order and the list depends
// only on the positions, so results are deterministic.
class NeighborList {
 public:
  NeighborList(double cutoff, double skin);

  double cutoff() const { return cutoff_; }
  double skin() const { return skin_; }

  // Sorted (i < j) pairs to leave out (bonded exclusions).
  void set_exclusions(std::vector<std::array<std::int32_t, 2>> excluded);

  void build(const std::vector<Vec3>& position, const Box& box);
  bool needs_rebuild(const std::vector<Vec3>& position) const;
  // Rebuilds if needed; returns whether it did.
  bool update(const std::vector<Vec3>& position, const Box& box);

  // Neighbours of i are neighbors()[offsets()[i] .. offsets()[i+1]).
  const std::vector<std::int32_t>& neighbors() const { return neighbors_; }
  const std::vector<std::size_t>& offsets() const { return offsets_; }
  std::size_t pair_count() const { return neighbors_.size(); }

  // When the box is at least three reaches wide along every periodic axis, each listed pair
  // also has a fixed periodic shift, valid until the next rebuild: x_i - x_j - shift is its
  // minimum-image separation, with no rounding in the force loop. Otherwise (small boxes)
  // image_codes() is empty and callers take minimum images.
  const std::vector<std::uint8_t>& image_codes() const { return image_codes_; }
  const std::array<Vec3, 27>& image_shifts() const { return image_shifts_; }
  std::int64_t builds() const { return builds_; }

 private:
  bool is_excluded(std::int32_t i, std::int32_t j) const;

  double cutoff_, skin_;
  std::vector<std::array<std::int32_t, 2>> excluded_;
  std::vector<std::size_t> excluded_offsets_;  // by first index, rebuilt with the list
  std::vector<std::int32_t> neighbors_;
  std::vector<std::size_t> offsets_;
  std::vector<std::uint8_t> image_codes_;
  std::array<Vec3, 27> image_shifts_{};
  std::vector<Vec3> position_at_build_;
  std::int64_t builds_ = 0;
};

}  // namespace deli
