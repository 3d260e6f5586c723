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
  begin_link(rows.size());
  link_ends_at(rows, 0, static_cast<std::int32_t>(particle_count_));
  end_link(rows.size());
}

void GrowingRowComponents::begin_link(std::size_t count) {
  next_.resize(2 * count);
  particle_.resize(2 * count);
}

void GrowingRowComponents::link_ends_at(const std::vector<Constraint>& rows, std::int32_t begin,
                                        std::int32_t end) {
  const std::size_t count = particle_.size() / 2;
  auto mine = [begin, end](std::int32_t particle) { return particle >= begin && particle < end; };
  for (std::size_t r = linked_; r < count; ++r) {
    const std::int32_t ends[2] = {rows[r].i, rows[r].j};
    for (std::size_t e = 0; e < 2; ++e) {
      const std::int32_t particle = ends[e];
      const std::size_t at = 2 * r + e;
      // A wall row's missing second particle is written with its first.
      if (!mine(particle < 0 ? ends[0] : particle)) continue;
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
}

void GrowingRowComponents::next_visit(Walker& walker) const {
  walker.visited_.resize(particle_.size() / 2, 0);
  if (++walker.visit_ == 0) {
    std::fill(walker.visited_.begin(), walker.visited_.end(), 0);
    walker.visit_ = 1;
  }
}

}  // namespace deli
