#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <vector>

#include "core/chunk_balance.hpp"
#include "core/thread_team.hpp"

namespace deli {

// Threads the loops below use: OpenMP's count (OMP_NUM_THREADS, else all cores; `deli run
// --threads` and [run] threads set it); 1 in a build without OpenMP. The loops run on deli's
// own team of threads (core/thread_team.hpp), not in OpenMP parallel regions.
int thread_count();
// n >= 1. Throws std::invalid_argument in a build without OpenMP when n > 1.
void set_thread_count(int n);
// The count where none is asked for (no --threads, no [run] threads): OMP_NUM_THREADS where
// set, else OpenMP's default (the CPUs of the affinity mask) lowered to the CPUs a cgroup's
// CPU quota allows (quota_cpus(), core/cpu_quota.hpp). Returns the count where the quota
// lowered it, else 0.
int use_default_thread_count();

// Below this many items a loop of substantial items (a particle's pairs or cell scan) runs
// on the calling thread alone: starting a parallel region costs microseconds.
inline constexpr std::size_t kParallelMinimum = 1024;

// How many chunks a loop over n substantial items is cut into: the thread count, or 1 for
// short loops.
inline int chunks_for(std::size_t n) {
  return n < kParallelMinimum ? 1 : thread_count();
}

// Loops whose items are a few arithmetic operations each (a particle's kick, drift or
// displacement test, a row's gap) give each chunk at least this many items (512 unless set):
// a job on the team costs as much as hundreds of such items. So 2 threads split them from 1024
// items, 8 threads from 4096 in full. On an idle AMD EPYC (Zen 3, 2 cores: an empty job 0.27
// us, a kick over 4000 particles 3.2 us on one thread and 1.8 us in two chunks;
// bench/parallel_overhead), against chunks of 8192 items (split from 16384 on 2 threads, the
// default before stop 49), loop time on 2 threads: the 4000-sphere fluid 0.64x, the default
// input 0.84-0.88x, LJ 4000 0.95x, the rigid melt 0.99-1.01x (bench/README.md, stops 44 and
// 49). Where a job costs microseconds (OpenMP's parallel regions on the machine of stops
// 28-42: 3.2 us) chunks of 512 made the 4000-sphere fluid 1.5x slower than one thread:
// [run] split_small_loops = false keeps the larger chunks (kUnsplitCheapChunk).
// The chunks, like every split here, depend on n and the thread count alone; they change the
// sums' grouping on several threads, so a run's split is its input's.
std::size_t cheap_chunk_minimum();
// For tests, which run the split paths of these loops on small systems, and for
// [run] split_small_loops.
void set_cheap_chunk_minimum(std::size_t n);
inline constexpr std::size_t kUnsplitCheapChunk = 8192;
inline constexpr std::size_t kUnsplitClusterChunk = 1024;

// Chunks of at least `minimum` of n items each, one per thread at most.
inline int chunks_of_at_least(std::size_t n, std::size_t minimum) {
  const std::size_t fit = n / std::max<std::size_t>(minimum, 1);
  return static_cast<int>(
      std::clamp<std::size_t>(fit, 1, static_cast<std::size_t>(thread_count())));
}

// Chunks for a loop over n cheap items: one per cheap_chunk_minimum() items, one per thread at
// most.
inline int chunks_for_cheap(std::size_t n) {
  return chunks_of_at_least(n, cheap_chunk_minimum());
}

// Chunks for a loop over `rows` rows (candidate contacts) that read the data of particles
// anywhere, written by a pass over the `particles` particles split as cheap items: chunks of
// rows from kParallelMinimum where that pass ran in chunks, else 1. Each thread then reads
// lines of its own in part; one thread reading them all would fetch the others' one line at a
// time (hs_32000 on 2 threads: the feasibility guard's scan 0.394 -> 0.209 s per 1000 steps),
// and rows split over particles one thread wrote would fetch that thread's (hs_4000: 0.055 ->
// 0.151 s).
inline int chunks_for_rows_of(std::size_t particles, std::size_t rows) {
  return chunks_for_cheap(particles) > 1 ? chunks_for(rows) : 1;
}

// A cluster loop (rod chains' solves and projections, by cluster) gives each chunk at least
// this many rows (256 unless set). The default input (30 chains of 40 beads, 1170 rods) on 2
// threads, its cluster loops split with its cheap loops against neither split: loop 0.88x
// (stop 49). Split alone, with its particle passes on one thread, they cost more than they
// saved (loop 1.01x: the position update 1.34x slower, each thread's solves reading lines the
// other core wrote; at stop 39, with OpenMP's regions, the loop 1.16x slower).
std::size_t cluster_chunk_minimum();
// For tests, which run the split paths of these loops on small systems, and for
// [run] split_small_loops.
void set_cluster_chunk_minimum(std::size_t n);

// Chunks for a loop over `items` items of uneven size holding `work` units in all (a
// cluster loop: its rows): one per cluster_chunk_minimum() units, one per thread and one per
// item at most.
inline int chunks_for_work(std::size_t items, std::size_t work) {
  const int by_work = chunks_of_at_least(work, cluster_chunk_minimum());
  return items < static_cast<std::size_t>(by_work) ? std::max(static_cast<int>(items), 1) : by_work;
}

struct IndexRange {
  std::size_t begin, end;
};
// Chunk c of `chunks` contiguous chunks of [0, n): near-equal, or, in a loop of one chunk a
// thread, at the shares the threads' speeds set (core/chunk_balance.hpp). Only for loops
// whose numbers do not depend on where the chunks begin; sums over chunks take
// fixed_chunk_range.
inline IndexRange chunk_range(std::size_t n, int c, int chunks) {
  return {balanced_chunk_begin(n, c, chunks), balanced_chunk_begin(n, c + 1, chunks)};
}
// Chunk c of `chunks` contiguous, near-equal chunks of [0, n), whatever the threads' speeds:
// the chunks of a sum whose grouping sets its last bits.
inline IndexRange fixed_chunk_range(std::size_t n, int c, int chunks) {
  const auto k = static_cast<std::size_t>(chunks);
  return {n * static_cast<std::size_t>(c) / k, n * static_cast<std::size_t>(c + 1) / k};
}

// The starts of `chunks` contiguous chunks of [0, n) holding near-equal work, item i's being
// [offsets[i], offsets[i + 1]) (ascending): chunk c starts at the first item whose work begins
// at or past c chunks-ths of it all (or, as chunk_range, at the threads' shares of it);
// starts[chunks] = n. `fixed`: near-equal work whatever the threads' speeds.
inline void equal_work_starts(const std::size_t* offsets, std::size_t n, int chunks,
                              std::vector<std::size_t>& starts, bool fixed = false) {
  const auto k = static_cast<std::size_t>(chunks);
  starts.assign(k + 1, n);
  starts[0] = 0;
  const std::size_t work = offsets[n] - offsets[0];
  for (std::size_t c = 1; c < k; ++c) {
    const std::size_t share =
        offsets[0] + (fixed ? fixed_chunk_range(work, static_cast<int>(c), chunks).begin
                            : chunk_range(work, static_cast<int>(c), chunks).begin);
    starts[c] = static_cast<std::size_t>(std::lower_bound(offsets, offsets + n, share) - offsets);
  }
}

// One value per chunk, on the stack for up to 16 chunks: a GVI step of the 4000-sphere fluid
// runs some twenty loops, and their heap blocks (allocated and freed by the calling thread
// while the others wait) were 2 % of its samples on two threads.
template <class T>
class ChunkSlots {
 public:
  explicit ChunkSlots(std::size_t count, const T& value = T{}) : count_(count) {
    if (count > kInline) {
      heap_.assign(count, value);
    } else {
      std::fill_n(inline_.begin(), count, value);
    }
  }
  T* begin() { return count_ > kInline ? heap_.data() : inline_.data(); }
  T* end() { return begin() + count_; }
  T& operator[](std::size_t k) { return begin()[k]; }

 private:
  static constexpr std::size_t kInline = 16;
  std::size_t count_;
  std::array<T, kInline> inline_{};
  std::vector<T> heap_;
};

namespace detail {
// One thread's share of a chunked loop: body(c, begin, end) for its chunks c = thread,
// thread + threads, ... of [0, n), each exception kept in failed[c] (the caller rethrows).
template <bool kFixed = false, class Body>
void chunks_of_thread(std::size_t n, int chunks, int thread, int threads, Body& body,
                      std::exception_ptr* failed) {
  for (int c = thread; c < chunks; c += threads) {
    try {
      const IndexRange r = kFixed ? fixed_chunk_range(n, c, chunks) : chunk_range(n, c, chunks);
      body(c, r.begin, r.end);
    } catch (...) {
      failed[c] = std::current_exception();
    }
  }
}
// The same with chunk c the items [starts[c], starts[c + 1]).
template <class Body>
void ranges_of_thread(const std::size_t* starts, int chunks, int thread, int threads, Body& body,
                      std::exception_ptr* failed) {
  for (int c = thread; c < chunks; c += threads) {
    try {
      body(c, starts[c], starts[c + 1]);
    } catch (...) {
      failed[c] = std::current_exception();
    }
  }
}
// for_each_chunk (below), in fixed_chunk_range's chunks where kFixed (not measured for the
// threads' shares).
template <bool kFixed, class Body>
void chunks_on_team(std::size_t n, int chunks, Body& body) {
  if (chunks <= 1) {
    body(0, std::size_t{0}, n);
    return;
  }
  ChunkSlots<std::exception_ptr> failed(static_cast<std::size_t>(chunks));
  auto job = [&](int thread, int threads) {
    chunks_of_thread<kFixed>(n, chunks, thread, threads, body, failed.begin());
  };
  if constexpr (kFixed) {
    const UnbalancedJobs unmeasured;
    run_on_team(std::min(chunks, thread_count()), job);
  } else {
    run_on_team(std::min(chunks, thread_count()), job);
  }
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
}
}  // namespace detail

// Runs body(c, begin, end) for the chunks c = 0..chunks-1 of [0, n) (chunk_range's: at the
// threads' shares where the loop has one chunk a thread), in parallel. Which thread runs a
// chunk changes nothing; a result whose numbers depend on where the chunks begin (a sum
// combined chunk by chunk) takes for_each_fixed_chunk. An exception from a chunk is rethrown
// once all have finished: the lowest chunk's, the one a serial loop would have met first.
template <class Body>
void for_each_chunk(std::size_t n, int chunks, Body&& body) {
  detail::chunks_on_team<false>(n, chunks, body);
}

// for_each_chunk in fixed_chunk_range's chunks, whatever the threads' speeds: for sums over
// chunks, combined in chunk order, the same on every run.
template <class Body>
void for_each_fixed_chunk(std::size_t n, int chunks, Body&& body) {
  detail::chunks_on_team<true>(n, chunks, body);
}

// for_each_chunk with chunks of the caller's choosing: chunk c is the items [starts[c],
// starts[c + 1]) (ascending).
template <class Body>
void for_each_range(const std::vector<std::size_t>& starts, Body&& body) {
  const int chunks = static_cast<int>(starts.size()) - 1;
  if (chunks <= 1) {
    body(0, starts.front(), starts.back());
    return;
  }
  ChunkSlots<std::exception_ptr> failed(static_cast<std::size_t>(chunks));
  auto job = [&](int thread, int threads) {
    detail::ranges_of_thread(starts.data(), chunks, thread, threads, body, failed.begin());
  };
  run_on_team(std::min(chunks, thread_count()), job);
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
}

// for_each_chunk_then with chunks of the caller's choosing: chunk c of the first pass is the
// items [first_starts[c], first_starts[c + 1]), of the second [second_starts[c],
// second_starts[c + 1]) (each ascending, as many chunks in both), chunk c of both on one thread.
template <class First, class Second>
void for_each_range_then(const std::vector<std::size_t>& first_starts,
                         const std::vector<std::size_t>& second_starts, First&& first,
                         Second&& second) {
  const int chunks = static_cast<int>(first_starts.size()) - 1;
  if (chunks <= 1) {
    first(0, first_starts.front(), first_starts.back());
    second(0, second_starts.front(), second_starts.back());
    return;
  }
  const auto slots = static_cast<std::size_t>(chunks);
  ChunkSlots<std::exception_ptr> failed(2 * slots);
  auto job = [&](int thread, int threads) {
    detail::ranges_of_thread(first_starts.data(), chunks, thread, threads, first, failed.begin());
    team_barrier();
    bool any = false;
    for (std::size_t c = 0; c < slots; ++c) any = any || failed[c] != nullptr;
    if (!any) {
      detail::ranges_of_thread(second_starts.data(), chunks, thread, threads, second,
                               failed.begin() + slots);
    }
  };
  run_on_team(std::min(chunks, thread_count()), job);
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
}

// for_each_chunk(n, chunks, first), then, once every chunk of it has ended, second(c, begin,
// end) for the chunks of [0, m): one job of the team, a barrier between the passes, and chunk
// c of both on one thread. Where the chunks of [0, m) are the particles the first pass's chunk c
// wrote most of, the second pass finds them in its own core's cache, and starts no job of its
// own. An exception from the first pass skips the second; the lowest chunk's exception is
// rethrown once all have finished, the first pass's before the second's.
template <class First, class Second>
void for_each_chunk_then(std::size_t n, std::size_t m, int chunks, First&& first, Second&& second) {
  const auto k = static_cast<std::size_t>(std::max(chunks, 1));
  std::vector<std::size_t> first_starts(k + 1, n), second_starts(k + 1, m);
  for (std::size_t c = 0; c < k; ++c) {
    first_starts[c] = chunk_range(n, static_cast<int>(c), static_cast<int>(k)).begin;
    second_starts[c] = chunk_range(m, static_cast<int>(c), static_cast<int>(k)).begin;
  }
  for_each_range_then(first_starts, second_starts, first, second);
}

// body(i) for every i in [0, n), cheap items independent of each other: the same result on
// any number of threads.
template <class Body>
void parallel_for(std::size_t n, Body&& body) {
  for_each_chunk(n, chunks_for_cheap(n), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) body(i);
  });
}

// to = from, chunk by chunk as the particle passes split (cheap items): each thread copies
// the lines it holds. Copied by the calling thread alone, every line of the other threads'
// chunks crossed to its core, and their next writes to either array waited for its copy to be
// dropped. (Only elements `to` gains are made by the calling thread, once.)
template <class T>
void copy_in_chunks(const std::vector<T>& from, std::vector<T>& to) {
  const std::size_t n = from.size();
  to.resize(n);
  for_each_chunk(n, chunks_for_cheap(n), [&](int, std::size_t begin, std::size_t end) {
    std::copy(from.begin() + static_cast<std::ptrdiff_t>(begin),
              from.begin() + static_cast<std::ptrdiff_t>(end),
              to.begin() + static_cast<std::ptrdiff_t>(begin));
  });
}

// join(k) in order for the items each chunk c of `chunks` over [0, n) kept at the start of its
// own stretch of `passing` (kept[c] of them): the calling thread reads only those.
template <class Kept, class Join>
void join_kept(std::size_t n, int chunks, const std::vector<std::uint32_t>& passing, Kept& kept,
               Join&& join) {
  for (int c = 0; c < chunks; ++c) {
    const std::size_t begin = chunk_range(n, c, chunks).begin;
    const std::size_t end = begin + kept[static_cast<std::size_t>(c)];
    for (std::size_t m = begin; m < end; ++m) join(passing[m]);
  }
}

// filter_in_order (below) with each chunk's items visited by visit(begin, end, pass), which
// calls pass(k) for the items k of [begin, end) that pass, in ascending order: for items read
// in runs (RowStretches::for_each), not one by one.
template <class Visit, class Join>
void filter_in_order_visiting(std::size_t n, int chunks, std::vector<std::uint32_t>& passing,
                              Visit&& visit, Join&& join) {
  if (chunks <= 1) {
    visit(std::size_t{0}, n, [&](std::size_t k) { join(k); });
    return;
  }
  passing.resize(n);
  ChunkSlots<std::size_t> kept(static_cast<std::size_t>(chunks));
  for_each_chunk(n, chunks, [&](int c, std::size_t begin, std::size_t end) {
    std::size_t at = begin;
    visit(begin, end, [&](std::size_t k) { passing[at++] = static_cast<std::uint32_t>(k); });
    kept[static_cast<std::size_t>(c)] = at - begin;
  });
  join_kept(n, chunks, passing, kept, join);
}

// The serial loop `for (k < n) if (test(k)) join(k);` with the tests (independent of each
// other and of the joins) on several threads: each chunk keeps the items that passed at the
// start of its own stretch of `passing`, then the joins are made in order on the calling
// thread, which reads only those (few, where a filter keeps few). One chunk: the serial
// loop itself.
template <class Test, class Join>
void filter_in_order(std::size_t n, int chunks, std::vector<std::uint32_t>& passing, Test&& test,
                     Join&& join) {
  filter_in_order_visiting(
      n, chunks, passing,
      [&](std::size_t begin, std::size_t end, auto&& pass) {
        for (std::size_t k = begin; k < end; ++k) {
          if (test(k)) pass(k);
        }
      },
      join);
}
// The tests split as cheap items.
template <class Test, class Join>
void filter_in_order(std::size_t n, std::vector<std::uint32_t>& passing, Test&& test, Join&& join) {
  filter_in_order(n, chunks_for_cheap(n), passing, test, join);
}

namespace detail {
// m = std::max(m, term(i)) for i in [begin, end), in a function of its own: inlined where m
// then lived on across calls, the compiler kept m in memory throughout, a store and a load
// on the chain at every item (the 4000-sphere fluid's serial pass: 8-10 cycles a particle).
template <class Term>
[[gnu::noinline]] double max_over(std::size_t begin, std::size_t end, double m, Term& term) {
  for (std::size_t i = begin; i < end; ++i) {
    const double t = term(i);
    m = m < t ? t : m;  // std::max(m, t): a NaN term is passed over
  }
  return m;
}
}  // namespace detail

// ordered_max (below), with before(begin, end) run on each chunk's items before its terms
// and after(begin, end) once its maximum is taken, in the same job: passes that make the
// terms' inputs, or need their outputs but not the maximum.
template <class Before, class Term, class After>
double ordered_max_around(std::size_t n, double start, Before&& before, Term&& term,
                          After&& after) {
  const int chunks = chunks_for_cheap(n);
  if (chunks == 1) {
    before(std::size_t{0}, n);
    const double m = detail::max_over(0, n, start, term);
    after(std::size_t{0}, n);
    return m;
  }
  ChunkSlots<double> partial(static_cast<std::size_t>(chunks), start);
  for_each_chunk(n, chunks, [&](int c, std::size_t begin, std::size_t end) {
    before(begin, end);
    partial[static_cast<std::size_t>(c)] = detail::max_over(begin, end, start, term);
    after(begin, end);
  });
  double m = start;
  for (const double p : partial) m = std::max(m, p);
  return m;
}
template <class Term, class After>
double ordered_max_then(std::size_t n, double start, Term&& term, After&& after) {
  return ordered_max_around(
      n, start, [](std::size_t, std::size_t) {}, term, after);
}

// What the serial loop `m = start; for (i < n) m = std::max(m, term(i));` finds (term(i) may
// also write item i's outputs): each chunk takes its maximum, the chunks' maxima are taken
// in chunk order. The maximum is exact, and a NaN term is passed over as the serial loop
// passes it over, so the result is the serial loop's on any number of threads.
template <class Term>
double ordered_max(std::size_t n, double start, Term&& term) {
  return ordered_max_then(n, start, term, [](std::size_t, std::size_t) {});
}

// The sum over i in [0, n) of term(i) (T: double, Vec3, SymTensor): each chunk sums its
// items in order, the chunk sums are added in chunk order. One chunk is the serial loop's
// sum bit for bit; more chunks regroup the additions (round-off, fixed per thread count:
// equal chunks, whatever the threads' speeds).
template <class T, class Term>
T ordered_sum(std::size_t n, Term&& term) {
  const int chunks = chunks_for_cheap(n);
  ChunkSlots<T> partial(static_cast<std::size_t>(chunks));
  for_each_fixed_chunk(n, chunks, [&](int c, std::size_t begin, std::size_t end) {
    T sum{};
    for (std::size_t i = begin; i < end; ++i) sum += term(i);
    partial[static_cast<std::size_t>(c)] = sum;
  });
  T total = partial[0];
  for (std::size_t c = 1; c < static_cast<std::size_t>(chunks); ++c) total += partial[c];
  return total;
}

}  // namespace deli
