#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace deli {

// Where a loop's chunks begin when it has one chunk per thread of the team: at shares of the
// items set by the threads' measured speeds (dynamic load balancing, as GROMACS' -dlb), moved
// between steps. Two vCPUs of one machine ran up to 29 % apart, either way round from run to
// run; split in halves, the faster thread waited for the slower at the end of every loop
// (hard-sphere fluid, 4000 spheres: 1-21 % of the two-thread loop, bench/README.md, "Stop 71").
// Only loops whose numbers do not depend on where their chunks begin follow the shares (each
// item's outputs its own, maxima, counts, concatenations in item order); sums over chunks and
// the force loops' per-chunk buffers keep equal chunks (fixed_chunk_range, core/parallel.hpp),
// so that a run's numbers are the same whatever the speeds were.

// On by default; [run] balance_threads = false keeps equal chunks everywhere.
void set_chunk_balance(bool on);

// The first item of chunk c (0 <= c <= chunks) of [0, n): at the shares where `chunks` is the
// count they are held for, else n c / chunks. Ascending in c; 0 at c = 0 and n at c = chunks.
std::size_t balanced_chunk_begin(std::size_t n, int c, int chunks);

// The shares held (empty: equal chunks). For tests, set_chunk_shares holds `shares` (their
// sum 1, each positive) for loops of shares.size() chunks until the next call, and clears
// what was measured; an empty vector goes back to equal chunks.
std::vector<double> chunk_shares();
void set_chunk_shares(const std::vector<double>& shares);

// Called by the team (core/thread_team.cpp): thread t of a job of `threads` threads, run in
// chunks that follow the shares, was busy for `ns` (its waits at barriers left out).
bool chunk_balance_measures(int threads);
void add_balanced_busy(int thread, std::int64_t ns);

// Moves the shares of `threads` threads towards the speeds measured since the last move, once
// enough was measured (a few milliseconds): called between steps (run_loop.cpp), never while
// a loop runs. With the balance off or one thread, nothing.
void rebalance_chunks(int threads);
// The moves rebalance_chunks made since the process started.
long long chunk_balance_moves();

// The shares after one move (pure, for tests): each thread's speed is its share over its busy
// time, and each share moves halfway towards its speed's fraction of them all, kept within
// half and one and a half times an equal share.
std::vector<double> moved_shares(const std::vector<double>& shares,
                                 const std::vector<double>& busy);

// Within its scope the calling thread's jobs are not measured: loops in equal chunks
// (fixed_chunk_range), whose times say nothing about the shares.
class UnbalancedJobs {
 public:
  UnbalancedJobs();
  ~UnbalancedJobs();
  UnbalancedJobs(const UnbalancedJobs&) = delete;
  UnbalancedJobs& operator=(const UnbalancedJobs&) = delete;
};

}  // namespace deli
