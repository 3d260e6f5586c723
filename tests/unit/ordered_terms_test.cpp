#include "core/ordered_terms.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

namespace deli {
namespace {

// Terms whose sum depends on the order they are added in (1e16 absorbs a 1 added after it).
std::vector<std::vector<double>> terms_of_items() {
  return {{1.0, 1e16, 1.0}, {}, {-1e16, 1.0, 1.0, 1.0}, {3.0}};
}

double serial_sum(const std::vector<std::vector<double>>& items) {
  double total = 0.0;
  for (const std::vector<double>& terms : items) {
    for (const double t : terms) total += t;
  }
  return total;
}

// Items adding their terms in any interleaving (as threads would), the total is the serial
// loop's running sum bit for bit, with the counts kept per line (per thread) or packed.
TEST(OrderedTerms, AnyInterleavingGivesTheSerialRunningSum) {
  const std::vector<std::vector<double>> items = terms_of_items();
  for (const bool per_thread : {false, true}) {
    OrderedTerms sum;
    sum.reset(
        items.size(), [&](std::size_t k) { return items[k].size() + 1; }, per_thread);
    // Last item first, each term of an item after the next item's.
    for (std::size_t round = 0; round < 4; ++round) {
      for (std::size_t k = items.size(); k-- > 0;) {
        if (round < items[k].size()) sum.add(k, items[k][round]);
      }
    }
    double total = 0.0;
    sum.add_to(total);
    EXPECT_EQ(total, 6.0) << "per_thread " << per_thread;
    // The order matters for these terms: added as made, they sum to 7.
    EXPECT_EQ(serial_sum(items), 6.0);
  }
}

// take() hands an item its next slots, after the terms it added.
TEST(OrderedTerms, TakenSlotsFollowTheItemsTerms) {
  for (const bool per_thread : {false, true}) {
    OrderedTerms sum;
    sum.reset(
        2, [](std::size_t) { return 3; }, per_thread);
    sum.add(1, 1e16);
    double* slots = sum.take(1, 2);
    slots[0] = 1.0;
    slots[1] = 1.0;
    sum.add(0, -1e16);
    double total = 0.0;
    sum.add_to(total);
    EXPECT_EQ(total, ((-1e16 + 1e16) + 1.0) + 1.0) << "per_thread " << per_thread;
  }
}

// Rows set in any order (as threads would, each its own rows), skipping some, the total is
// the running sum of the set rows in row order; another reset forgets them.
TEST(TermsByRow, AnyOrderOfRowsGivesTheRowOrderSum) {
  // In row order: ((1 + 1e16) + -1e16) + 1 = 1, row 2 left unset; made in the order of the
  // rows the result would be 2 or 0.
  const std::vector<double> terms = {1.0, 1e16, 5.0, -1e16, 1.0};
  TermsByRow sum;
  sum.reset(terms.size());
  for (const std::size_t row : {4, 3, 0, 1}) sum.set(row, terms[row]);
  double total = 0.0;
  sum.add_to(total);
  EXPECT_EQ(total, ((1.0 + 1e16) + -1e16) + 1.0);
  EXPECT_EQ(total, 1.0);
  sum.reset(2);
  sum.set(1, 3.0);
  total = 0.5;
  sum.add_to(total);
  EXPECT_EQ(total, 3.5);
}

}  // namespace
}  // namespace deli
