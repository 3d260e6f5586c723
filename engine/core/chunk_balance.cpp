#include "core/chunk_balance.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace deli {

namespace {

// Teams of up to this many threads are balanced; larger ones keep equal chunks.
constexpr int kMostBalanced = 64;
// Measured time (all threads together) before a move: under it one slow job of a few hundred
// microseconds, a page fault or another process's time slice would move the shares.
constexpr double kMeasuredBeforeMove = 4e6;  // ns

bool balance_on = true;
// The shares' running sums: loops of `held_chunks` chunks begin chunk c at n cumulative[c].
int held_chunks = 0;
bool held_equal = true;  // equal shares: n c / chunks, exactly as without any
std::array<double, kMostBalanced + 1> cumulative{};
std::array<double, kMostBalanced> shares{};

// Each thread's busy time since the last move, written by that thread alone (its own line);
// read by the calling thread between steps, once every job has ended.
struct alignas(64) Busy {
  std::int64_t ns = 0;
};
std::array<Busy, kMostBalanced> busy{};

thread_local int unbalanced_depth = 0;
long long moves = 0;

void hold(const std::vector<double>& s) {
  held_chunks = static_cast<int>(s.size());
  held_equal = std::all_of(s.begin(), s.end(), [&](double x) { return x == s.front(); });
  double sum = 0.0;
  cumulative[0] = 0.0;
  for (std::size_t c = 0; c < s.size(); ++c) {
    shares[c] = s[c];
    sum += s[c];
    cumulative[c + 1] = sum;
  }
  for (std::size_t c = 1; c < s.size(); ++c) cumulative[c] /= sum;
  cumulative[s.size()] = 1.0;
  for (Busy& b : busy) b.ns = 0;
}

}  // namespace

void set_chunk_balance(bool on) {
  balance_on = on;
  if (!on) hold({});
}

std::size_t balanced_chunk_begin(std::size_t n, int c, int chunks) {
  if (chunks != held_chunks || held_equal || c <= 0 || c >= chunks) {
    return n * static_cast<std::size_t>(c) / static_cast<std::size_t>(chunks);
  }
  // Ascending in c: the running sums ascend, and product and floor keep their order.
  const double at = std::floor(static_cast<double>(n) * cumulative[static_cast<std::size_t>(c)]);
  return std::min(n, static_cast<std::size_t>(at));
}

std::vector<double> chunk_shares() {
  return std::vector<double>(shares.begin(), shares.begin() + held_chunks);
}

void set_chunk_shares(const std::vector<double>& s) {
  if (s.size() > static_cast<std::size_t>(kMostBalanced)) {
    hold({});
    return;
  }
  hold(s);
}

bool chunk_balance_measures(int threads) {
  return balance_on && threads > 1 && threads == held_chunks && unbalanced_depth == 0;
}

void add_balanced_busy(int thread, std::int64_t ns) {
  busy[static_cast<std::size_t>(thread)].ns += ns;
}

std::vector<double> moved_shares(const std::vector<double>& s, const std::vector<double>& b) {
  const std::size_t k = s.size();
  std::vector<double> speed(k);
  double total = 0.0;
  for (std::size_t t = 0; t < k; ++t) {
    speed[t] = b[t] > 0.0 ? s[t] / b[t] : 0.0;
    total += speed[t];
  }
  if (!(total > 0.0) || std::find(speed.begin(), speed.end(), 0.0) != speed.end()) return s;
  const double equal = 1.0 / static_cast<double>(k);
  std::vector<double> out(k);
  double sum = 0.0;
  for (std::size_t t = 0; t < k; ++t) {
    const double moved = s[t] + 0.5 * (speed[t] / total - s[t]);
    out[t] = std::clamp(moved, 0.5 * equal, 1.5 * equal);
    sum += out[t];
  }
  for (double& share : out) share /= sum;
  return out;
}

void rebalance_chunks(int threads) {
  if (!balance_on || threads < 2 || threads > kMostBalanced) return;
  if (held_chunks != threads) {
    hold(
        std::vector<double>(static_cast<std::size_t>(threads), 1.0 / static_cast<double>(threads)));
    return;
  }
  // Called every step: the measured times summed first, their list made only for a move (a
  // heap block a step on the calling thread, while the others wait, otherwise).
  double total = 0.0;
  for (int t = 0; t < threads; ++t)
    total += static_cast<double>(busy[static_cast<std::size_t>(t)].ns);
  if (total < kMeasuredBeforeMove) return;
  std::vector<double> measured(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) {
    measured[static_cast<std::size_t>(t)] =
        static_cast<double>(busy[static_cast<std::size_t>(t)].ns);
  }
  hold(moved_shares(chunk_shares(), measured));
  ++moves;
}

long long chunk_balance_moves() {
  return moves;
}

UnbalancedJobs::UnbalancedJobs() {
  ++unbalanced_depth;
}
UnbalancedJobs::~UnbalancedJobs() {
  --unbalanced_depth;
}

}  // namespace deli
