#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "constraints/constraint.hpp"

namespace deli {

// The connected components (rows joined where they share a particle) of a list of rows that
// only grows between calls, as the active set's rounds grow it within a step: each row is
// linked to its particles once, when it arrives, and a call walks from given seed rows to
// their components alone. The active set's later rounds add a row or two to about a hundred
// (the 4000-sphere fluid); classifying and clustering every row again at each round took
// as long on two threads as on one.
class GrowingRowComponents {
 public:
  // One walker's marks of the rows it has found: threads that walk the same links at once
  // each hold their own.
  class Walker {
    friend class GrowingRowComponents;
    std::uint32_t visit_ = 0;             // the walk's number: visited_ holds it for its rows
    std::vector<std::uint32_t> visited_;  // per row
    std::vector<std::int32_t> found_;     // the component being walked
  };

  // A new list of rows over `particle_count` particles: none linked.
  void restart(std::size_t particle_count);
  // Whether rows [0, count) over `particle_count` particles are the rows linked.
  bool continues(std::size_t particle_count, std::size_t count) const {
    return particle_count == particle_count_ && count == linked_ && linked_ > 0;
  }
  // Links rows [linked, rows.size()): the rows before are those linked already.
  void link(const std::vector<Constraint>& rows);
  // link() in parts, for threads that split the particles: begin_link(rows.size()), then
  // link_ends_at(rows, begin, end) for particle ranges that cover [0, particle_count), at
  // once on several threads, then end_link(rows.size()). Each particle's ends are linked in
  // the order link() links them, by the one call whose range holds it.
  void begin_link(std::size_t count);
  void link_ends_at(const std::vector<Constraint>& rows, std::int32_t begin, std::int32_t end);
  void end_link(std::size_t count) { linked_ = count; }
  std::size_t linked() const { return linked_; }

  // visit(rows, count) for each component that holds one of the seed rows, once each: its
  // rows in the order the walk found them, the seed first.
  template <class Visit>
  void components_of(const std::int32_t* seeds, std::size_t seed_count, Visit&& visit) {
    components_of(walker_, seeds, seed_count, visit);
  }
  // The same with the walker's own marks (the rows linked or being linked: after
  // begin_link, once every link_ends_at has returned): several threads at once, each with its
  // own walker.
  template <class Visit>
  void components_of(Walker& walker, const std::int32_t* seeds, std::size_t seed_count,
                     Visit&& visit) const {
    next_visit(walker);
    std::vector<std::uint32_t>& visited = walker.visited_;
    const std::uint32_t visit_number = walker.visit_;
    std::vector<std::int32_t>& found = walker.found_;
    for (std::size_t s = 0; s < seed_count; ++s) {
      const std::int32_t seed = seeds[s];
      if (visited[static_cast<std::size_t>(seed)] == visit_number) continue;
      visited[static_cast<std::size_t>(seed)] = visit_number;
      if (alone(seed)) {
        visit(&seed, std::size_t{1});
        continue;
      }
      found.clear();
      found.push_back(seed);
      for (std::size_t k = 0; k < found.size(); ++k) {
        const std::int32_t row = found[k];
        for (int end = 0; end < 2; ++end) {
          const std::int32_t particle = particle_[2 * static_cast<std::size_t>(row) + end];
          if (particle < 0) continue;
          for (std::int32_t at = head_[static_cast<std::size_t>(particle)]; at >= 0;
               at = next_[static_cast<std::size_t>(at)]) {
            const std::int32_t other = at >> 1;
            if (visited[static_cast<std::size_t>(other)] == visit_number) continue;
            visited[static_cast<std::size_t>(other)] = visit_number;
            found.push_back(other);
          }
        }
      }
      visit(found.data(), found.size());
    }
  }

 private:
  // A new walk's number, its marks sized for the rows linked.
  void next_visit(Walker& walker) const;
  // Whether the row shares no particle with another: at each of its particles its end is the
  // last linked and was linked first. Most contact rows are alone (the 4000-sphere fluid: 90 %);
  // the test reads four numbers where the walk took 20 ns a row, in branches it mispredicts.
  bool alone(std::int32_t row) const {
    bool alone = true;
    for (std::size_t end = 0; end < 2; ++end) {
      const std::size_t at = 2 * static_cast<std::size_t>(row) + end;
      const std::int32_t particle = particle_[at];
      if (particle < 0) continue;
      alone = alone && head_[static_cast<std::size_t>(particle)] == static_cast<std::int32_t>(at) &&
              next_[at] < 0;
    }
    return alone;
  }

  std::size_t particle_count_ = 0;
  std::size_t linked_ = 0;
  std::uint32_t list_ = 0;  // the list's number: head_ is valid where head_list_ holds it
  std::vector<std::uint32_t> head_list_;
  std::vector<std::int32_t> head_;      // per particle: its last linked row end (2 row + end)
  std::vector<std::int32_t> next_;      // per row end: the particle's row end linked before
  std::vector<std::int32_t> particle_;  // per row end: the particle (-1: a wall row's second)
  Walker walker_;                       // components_of's without a walker of the caller's
};

}  // namespace deli
