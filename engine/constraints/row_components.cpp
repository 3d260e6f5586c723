#include "constraints/row_components.hpp"

#include <algorithm>

namespace deli {

void GrowingRowComponents::restart(std::size_t particle_count) {
  if (particle_count != particle_count_ || ++list_ == 0) {
    // A new particle count, or the lists' numbers wrapped: no head is valid.
    head_list_.assign(particle_count, 0);
    head_.resize(particle_count);
    list_ = 1;
  }
  particle_count_ = particle_count;
  linked_ = 0;
}

void GrowingRowComponents::link(const std::vector<Constraint>& rows) {
  const std::size_t count = rows.size();
  next_.resize(2 * count);
  particle_.resize(2 * count);
  visited_.resize(count, 0);
  for (std::size_t r = linked_; r < count; ++r) {
    const std::int32_t ends[2] = {rows[r].i, rows[r].j};
    for (std::size_t end = 0; end < 2; ++end) {
      const std::int32_t particle = ends[end];
      const std::size_t at = 2 * r + end;
      particle_[at] = particle;
      if (particle < 0) continue;
      const auto p = static_cast<std::size_t>(particle);
      if (head_list_[p] != list_) {
        head_list_[p] = list_;
        head_[p] = -1;
      }
      next_[at] = head_[p];
      head_[p] = static_cast<std::int32_t>(at);
    }
  }
  linked_ = count;
}

void GrowingRowComponents::next_visit() {
  if (++visit_ == 0) {
    std::fill(visited_.begin(), visited_.end(), 0);
    visit_ = 1;
  }
}

}  // namespace deli
