#pragma once

#include <cstddef>
#include <vector>

#include "core/cache_line.hpp"

namespace deli {

// The terms of a sum (a virial) that a loop over items makes item by item, possibly on
// several threads, added as the serial loop would have added them: item 0's terms in the
// order it made them, then item 1's, and so on. The total is the serial loop's running sum
// bit for bit, on any number of threads. Each item writes only its own slots.
class OrderedTerms {
 public:
  // Room for `items` items, item k making at most capacity(k) terms; no term made yet.
  // per_thread: the items are the threads' (a few, each adding many terms), and each item's
  // count of terms made is kept on a cache line of its own.
  template <class Capacity>
  void reset(std::size_t items, Capacity&& capacity, bool per_thread = false) {
    stride_ = per_thread ? kCountsALine : 1;
    begin_.resize(items + 1);
    made_.assign(items * stride_, 0);
    begin_[0] = 0;
    for (std::size_t k = 0; k < items; ++k) begin_[k + 1] = begin_[k] + capacity(k);
    terms_.resize(begin_[items]);
  }
  void add(std::size_t item, double term) { terms_[begin_[item] + made_[item * stride_]++] = term; }
  // Item k's next `count` slots, to be written by the caller.
  double* take(std::size_t item, std::size_t count) {
    double* slots = terms_.data() + begin_[item] + made_[item * stride_];
    made_[item * stride_] += count;
    return slots;
  }
  // total += every term, in item order.
  void add_to(double& total) const {
    for (std::size_t k = 0; k < made_.size() / stride_; ++k) {
      const std::size_t end = begin_[k] + made_[k * stride_];
      for (std::size_t t = begin_[k]; t < end; ++t) total += terms_[t];
    }
  }

 private:
  static constexpr std::size_t kCountsALine = kCacheLine / sizeof(std::size_t);
  std::size_t stride_ = 1;
  std::vector<std::size_t> begin_, made_;
  std::vector<double> terms_;
};

// The terms of a sum that a loop over rows makes, at most one a row, possibly on several
// threads and in any order, added in row order: the total is the same on any number of
// threads, whichever thread made which term. Each row's slot is written only by the thread
// that makes its term.
class TermsByRow {
 public:
  // Room for `rows` rows, no term made yet.
  void reset(std::size_t rows) {
    terms_.resize(rows);
    made_.assign(rows, 0);
  }
  void set(std::size_t row, double term) {
    terms_[row] = term;
    made_[row] = 1;
  }
  // total += every term made, in row order.
  void add_to(double& total) const {
    for (std::size_t r = 0; r < made_.size(); ++r) {
      if (made_[r]) total += terms_[r];
    }
  }

 private:
  std::vector<double> terms_;
  std::vector<char> made_;
};

}  // namespace deli
