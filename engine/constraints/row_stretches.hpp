#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "constraints/constraint.hpp"

namespace deli {

// Rows with their gaps in stretches, each left where it was written, read as their
// concatenation: row k of the whole is row k - start(s) of stretch s. The candidate rows of a
// step as the threads that screened them wrote them (NearbyRows::collect), without a copy
// joining them into one vector: on two threads the second chunk's thread copied its rows
// after the first chunk's at every call, 1.7 % of the 4000-sphere fluid's loop (measured by
// copying them twice, bench/README.md, "Stop 63"). The stretches are borrowed: they must
// neither move nor change while this reads them.
class RowStretches {
 public:
  // One stretch: `rows` and their `gaps` (as many).
  void assign(const std::vector<Constraint>& rows, const std::vector<double>& gaps) {
    rows_.clear();
    gaps_.clear();
    start_.assign(1, 0);
    add(rows, gaps);
  }
  void add(const std::vector<Constraint>& rows, const std::vector<double>& gaps) {
    rows_.push_back(rows.data());
    gaps_.push_back(gaps.data());
    start_.push_back(start_.back() + rows.size());
  }

  std::size_t size() const { return start_.back(); }
  std::size_t stretches() const { return rows_.size(); }
  // Stretch s's first row in the whole.
  std::size_t first_of(std::size_t s) const { return start_[s]; }
  const Constraint& operator[](std::size_t k) const {
    const std::size_t s = stretch_of(k);
    return rows_[s][k - start_[s]];
  }
  double gap(std::size_t k) const {
    const std::size_t s = stretch_of(k);
    return gaps_[s][k - start_[s]];
  }
  // body(k, row k, its gap) for k in [begin, end), stretch by stretch (no search per row).
  template <class Body>
  void for_each(std::size_t begin, std::size_t end, Body&& body) const {
    if (begin >= end) return;
    for (std::size_t s = stretch_of(begin), k = begin; k < end; ++s) {
      const std::size_t first = start_[s], last = std::min(end, start_[s + 1]);
      const Constraint* rows = rows_[s];
      const double* gaps = gaps_[s];
      for (; k < last; ++k) body(k, rows[k - first], gaps[k - first]);
    }
  }
  // The rows in one vector (and their gaps), for readers of whole vectors.
  void join(std::vector<Constraint>& rows, std::vector<double>& gaps) const {
    rows.clear();
    gaps.clear();
    for (std::size_t s = 0; s < stretches(); ++s) {
      const std::size_t count = start_[s + 1] - start_[s];
      rows.insert(rows.end(), rows_[s], rows_[s] + count);
      gaps.insert(gaps.end(), gaps_[s], gaps_[s] + count);
    }
  }

 private:
  std::size_t stretch_of(std::size_t k) const {
    std::size_t s = 0;
    while (k >= start_[s + 1]) ++s;
    return s;
  }

  std::vector<const Constraint*> rows_;
  std::vector<const double*> gaps_;
  std::vector<std::size_t> start_{0};  // stretch s's first row in the whole; then the size
};

}  // namespace deli
