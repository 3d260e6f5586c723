#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace deli {

// The items of [first, last) that pass a test, kept in order: test(k, slot) for each item k
// (slot: k's place in its block of kCompactBlock, for the test's own scratch), then
// emit(count, k, slot) for each item, count the number passed before it; a failed item's
// emit is overwritten by the next one's. Returns count plus the number passed.
//
// The tests run first, a block at a time, into flags, then the block is compacted. Fused
// (out[count] = k; count += test(k)), each store's address waits for the previous item's
// test, and the loop waited with it: a replica of the 32000-sphere fluid's first screen
// (two loads and a compare an item) took 7.0 ns an item, 1.4 ns with the tests first (AMD
// Zen 3), and in the fluid's run NearbyRows::screen_pairs took 0.57x its samples
// (bench/README.md, stop 52). Where each test is short, the fused loop is the faster: the
// masked pair Hessians' scan (a load and a compare an entry) took 1.4x its samples this way,
// the test of their reach 1.07x, the short list's scan of the neighbour list 1.07x.
inline constexpr std::size_t kCompactBlock = 256;
template <class Test, class Emit>
std::size_t compact_passing(std::size_t first, std::size_t last, std::size_t count, Test&& test,
                            Emit&& emit) {
  std::uint8_t passed[kCompactBlock];
  for (std::size_t base = first; base < last; base += kCompactBlock) {
    const std::size_t end = std::min(last, base + kCompactBlock);
    for (std::size_t k = base; k < end; ++k) passed[k - base] = test(k, k - base) ? 1 : 0;
    for (std::size_t k = base; k < end; ++k) {
      emit(count, k, k - base);
      count += passed[k - base];
    }
  }
  return count;
}

}  // namespace deli
