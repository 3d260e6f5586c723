#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace deli {

// For each of several chunks of a pair loop's items (slots: particles, or cell order's
// slots), the blocks of 16 consecutive items that the chunk touches: its own items' blocks
// and those of its items' listed partners. A chunk then gathers positions and zeroes forces
// on those blocks alone, and the pass that adds the chunks' forces reads each chunk's forces
// there alone, so that only lines of blocks the chunks share cross between cores.
// NeighborList::touched_blocks() makes them.
class TouchedBlocks {
 public:
  static constexpr unsigned kShift = 4;  // 16 slots a block: 512 bytes of padded positions

  static std::size_t block_of(std::size_t item) { return item >> kShift; }
  static std::size_t block_begin(std::size_t block) { return block << kShift; }

  struct Run {
    std::size_t begin, end;
  };

  int chunks() const { return static_cast<int>(marks_.size()); }
  std::size_t items() const { return items_; }
  bool touches(int c, std::size_t block) const {
    return marks_[static_cast<std::size_t>(c)][block] != 0;
  }
  // Chunk c's touched items as runs [begin, end), ascending.
  const std::vector<Run>& runs(int c) const { return runs_[static_cast<std::size_t>(c)]; }

  // For the maker: `chunks` chunks of `items` items, every mark clear.
  void clear(std::size_t items, int chunks) {
    items_ = items;
    marks_.resize(static_cast<std::size_t>(chunks));
    runs_.resize(static_cast<std::size_t>(chunks));
    for (std::vector<char>& m : marks_) {
      m.assign(block_of(items + (std::size_t{1} << kShift) - 1), 0);
    }
  }
  std::vector<char>& marks(int c) { return marks_[static_cast<std::size_t>(c)]; }
  // Chunk c's runs from its marks.
  void make_runs(int c) {
    const std::vector<char>& mark = marks_[static_cast<std::size_t>(c)];
    std::vector<Run>& runs = runs_[static_cast<std::size_t>(c)];
    runs.clear();
    for (std::size_t b = 0; b < mark.size(); ++b) {
      if (!mark[b]) continue;
      const std::size_t from = block_begin(b), to = std::min(block_begin(b + 1), items_);
      if (!runs.empty() && runs.back().end == from) {
        runs.back().end = to;
      } else {
        runs.push_back({from, to});
      }
    }
  }

 private:
  std::size_t items_ = 0;
  std::vector<std::vector<char>> marks_;  // per chunk, per block
  std::vector<std::vector<Run>> runs_;    // per chunk
};

}  // namespace deli
