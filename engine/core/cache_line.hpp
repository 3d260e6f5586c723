#pragma once

#include <cstddef>

namespace deli {

// A value alone on its cache line: slots that different threads write again and again (a
// per-thread count, bound or list) would otherwise share a line, which then crosses between
// their cores at every write (the 4000-sphere fluid's reflections on two threads: 10x the
// one-thread time in those writes where the cores were far apart).
inline constexpr std::size_t kCacheLine = 64;

template <class T>
struct alignas(kCacheLine) OnItsOwnLine {
  T value{};
};

}  // namespace deli
