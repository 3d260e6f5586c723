#include "constraints/nearby_rows.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/compact.hpp"
#include "core/parallel.hpp"

namespace deli {

void NearbyRows::make(const ConstraintSet& set, const Particles& particles, const Vec3* q,
                      const NeighborList& list, const Box& box, const double* particle_reach,
                      const RangePass* make_reaches) {
  const bool bonded_pairs = !set.unconstrained_pairs.empty();
  if (bonded_pairs) index_bonded_pairs(set, particles.size());
  shifted_ = list.coded();
  shifts_ = list.image_shifts();
  one_radius_ = std::all_of(particles.radius.begin(), particles.radius.end(),
                            [&](double r) { return r == particles.radius.front(); });
  one_contact_ = one_radius_ && !particles.radius.empty()
                     ? particles.radius.front() + particles.radius.front()
                     : 0.0;
  // The list where the build left it (its list by particle is not made for this).
  const NeighborList::PartnerRanges ranges = list.partner_ranges();
  // By chunks of the list's particles, each into its own pairs: joined in chunk order, the
  // serial scan's pairs in its order on any number of threads.
  // Split as cheap items, counted in listed pairs (a pair's test is a few operations): from
  // 1024 particles, hs_4000's 600 us scan (12700 pairs) took about 100 us more on two threads
  // of an idle 2-core machine than on one (bench/README.md, fuse); counted in particles, the
  // default input's 1200 beads with about 25 pairs each (LJ's reach) were scanned on one
  // thread at every build, and their rows screened on one thread at every call (two threads
  // split by pairs: its loop 0.93x, bench/README.md, "Stop 48").
  const std::size_t listed = ranges.particles;
  const int chunks = chunks_for_cheap(list.pair_count());
  scanned_.resize(static_cast<std::size_t>(chunks));
  // The anchor positions and the displacements since (none yet: each particle's reach, or
  // zero) are set by the chunk that scans the particle, on the thread whose lines they are.
  const std::size_t n = particles.size();
  anchor_.resize(n);
  moved_.resize(n);
  auto anchor = [&](std::size_t begin, std::size_t end) {
    std::copy(q + begin, q + end, anchor_.begin() + static_cast<std::ptrdiff_t>(begin));
    for (std::size_t i = begin; i < end; ++i) moved_[i] = particle_reach ? particle_reach[i] : 0.0;
  };
  const bool anchored_by_chunk = listed == n;
  // The reaches (per particle) before the anchors read them: each chunk's own where the
  // chunks anchor their particles.
  if (make_reaches && !anchored_by_chunk) (*make_reaches)(0, n);
  // The chunks hold near-equal listed pairs, not particles: split by particles, the first of
  // hs_4000's two chunks held 4 % more pairs than the second (6478 against 6210, the mean over
  // 346 builds), and its screen, at every collection in the step's largest job, 6 % more
  // instructions (0.8 % so split: bench/README.md, "Stop 67").
  std::vector<std::size_t>& starts = scan_starts_;
  if (chunks > 1 && ranges.end == ranges.begin + 1) {
    // The list by particle: its offsets are the running count already.
    equal_work_starts(ranges.begin, listed, chunks, starts);
  } else if (chunks > 1) {
    std::vector<std::size_t>& offsets = scan_offsets_;
    offsets.resize(listed + 1);
    offsets[0] = 0;
    for (std::size_t i = 0; i < listed; ++i) {
      offsets[i + 1] = offsets[i] + (ranges.end[i] - ranges.begin[i]);
    }
    equal_work_starts(offsets.data(), listed, chunks, starts);
  } else {
    starts.assign({std::size_t{0}, listed});
  }
  for_each_range(starts, [&](int c, std::size_t begin, std::size_t end) {
    ScannedChunk& chunk = scanned_[static_cast<std::size_t>(c)];
    chunk.pairs.clear();
    if (anchored_by_chunk && make_reaches) (*make_reaches)(begin, end);
    if (anchored_by_chunk) anchor(begin, end);
    scan_list(ranges, q, box, particles.radius.data(), bonded_pairs, begin, end, chunk.pairs);
  });
  if (!anchored_by_chunk) anchor(0, n);
  list_ = &list;
  list_builds_ = list.builds();
}

NearbyRows::Anchors NearbyRows::anchors_for(const NeighborList& list, std::size_t particle_count) {
  if (list_ != &list || list_builds_ != list.builds() || anchor_.size() != particle_count)
    return {};
  return {anchor_.data(), moved_.data()};
}

void NearbyRows::scan_list(const NeighborList::PartnerRanges& ranges, const Vec3* q, const Box& box,
                           const double* radius, bool bonded_pairs, std::size_t first,
                           std::size_t last, std::vector<Pair>& pairs) const {
  const std::int32_t* neighbors = ranges.neighbors;
  const std::uint8_t* codes = ranges.image_codes;
  const Vec3* shifts = shifts_.data();
  const bool shifted = shifted_;
  const double margin = margin_;
  // Generous by far more than rounding: no pair within contact + margin is dropped.
  auto beyond = [margin](double d2, double contact) {
    const double within = contact + margin;
    return d2 > within * within * (1.0 + 1e-6) + 1e-300;
  };
  // Entry k of owner i, at squared distance d2, as the pair a < b, unless bonded.
  auto add = [&](std::size_t i, std::size_t k, double d2) {
    const auto a = static_cast<std::int32_t>(std::min<std::size_t>(i, neighbors[k]));
    const auto b = static_cast<std::int32_t>(std::max<std::size_t>(i, neighbors[k]));
    if (bonded_pairs && bonded(a, b)) return;
    // At most the gap: the nearest float (within half a unit in its last place) less two units
    // and a floor for gaps near zero, rounded (half a unit) at most one and a half units down.
    // Without a branch (the nearest float is above the gap half the time, unpredictably). An
    // infinite or NaN gap gives NaN, which the first screen passes.
    const double gap = std::sqrt(d2) - (radius[a] + radius[b]);
    const auto nearest = static_cast<float>(gap);
    const float below = nearest - (std::abs(nearest) * 0x1p-22f + 0x1p-100f);
    const bool negated = shifted && a != static_cast<std::int32_t>(i);
    pairs.push_back({a, b, below, shifted ? codes[k] : std::uint8_t{0}, negated});
  };
  if (!shifted) {
    for (std::size_t i = first; i < last; ++i) {
      for (std::size_t k = ranges.begin[i]; k < ranges.end[i]; ++k) {
        const auto a = std::min<std::size_t>(i, neighbors[k]);
        const auto b = std::max<std::size_t>(i, neighbors[k]);
        const double d2 = norm2(box.minimum_image(q[a] - q[b]));
        if (!beyond(d2, radius[a] + radius[b])) add(i, k, d2);
      }
    }
    return;
  }
  // Through the list's shift, as collect() measures (the minimum image up to rounding):
  // q_i - q_j - s, the negation (exactly) of q_a - q_b less the oriented shift, so that its
  // square is the pair's either way. One entry in seven of the default input's is within
  // contact + margin, unpredictably, and nearly every entry has the zero shift: each owner's
  // entries are tested without a branch on the outcome (those within, and their squares,
  // gathered first), without the zero shift's subtraction (x - 0 is x but for the sign of a
  // zero, which squares alike), and, where every particle has one radius, against one bound.
  const auto unshifted = static_cast<std::uint8_t>(zero_shift_code(shifts));
  const bool one_radius = one_radius_;
  const double one_contact = one_contact_;
  auto separation2 = [&](const Vec3& qi, std::size_t k) {
    const std::uint8_t code = codes[k];
    const Vec3 d = qi - q[neighbors[k]];
    return norm2(code == unshifted ? d : d - shifts[code]);
  };
  std::uint32_t within[kScanBlock];
  double within_d2[kScanBlock];
  for (std::size_t i = first; i < last; ++i) {
    const Vec3 qi = q[i];
    const double ri = radius[i];
    for (std::size_t block = ranges.begin[i]; block < ranges.end[i]; block += kScanBlock) {
      const std::size_t block_end = std::min(ranges.end[i], block + kScanBlock);
      std::size_t count = 0;
      for (std::size_t k = block; k < block_end; ++k) {
        const double d2 = separation2(qi, k);
        const double contact = one_radius ? one_contact : ri + radius[neighbors[k]];
        within[count] = static_cast<std::uint32_t>(k - block);
        within_d2[count] = d2;
        count += beyond(d2, contact) ? 0 : 1;
      }
      for (std::size_t m = 0; m < count; ++m) add(i, block + within[m], within_d2[m]);
    }
  }
}

void NearbyRows::index_bonded_pairs(const ConstraintSet& set, std::size_t particle_count) {
  const auto& pairs = set.unconstrained_pairs;
  if (bonded_source_ == &pairs && bonded_count_ == pairs.size() &&
      bonded_first_.size() == particle_count + 1) {
    return;
  }
  // Sorted by (a, b): each a's partners are one ascending run.
  bonded_first_.assign(particle_count + 1, 0);
  for (const auto& [a, b] : pairs) ++bonded_first_[a + 1];
  for (std::size_t i = 0; i < particle_count; ++i) bonded_first_[i + 1] += bonded_first_[i];
  bonded_partner_.resize(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) bonded_partner_[k] = pairs[k][1];
  bonded_source_ = &pairs;
  bonded_count_ = pairs.size();
}

bool NearbyRows::bonded(std::int32_t a, std::int32_t b) const {
  for (std::int32_t k = bonded_first_[a]; k < bonded_first_[a + 1]; ++k) {
    if (bonded_partner_[k] == b) return true;
  }
  return false;
}

bool NearbyRows::collect(const ConstraintSet& set, const Particles& particles, const Vec3* q,
                         const NeighborList& list, const Box& box, double reach,
                         const double* particle_reach, double exact_below,
                         std::vector<Constraint>& out, std::vector<double>& gap_at_q,
                         const RangePass* make_reaches, RowStretches* stretches,
                         const double* anchored_largest2, const StretchPass* then) {
  out.clear();
  gap_at_q.clear();
  // The screen's chunks 1.. left as stretches: nothing is appended after them.
  const bool leave_chunks = stretches != nullptr && set.walls.empty();
  std::size_t left_chunks = 0;  // chunks 1..left_chunks - 1 left
  // The reaches made in a job of their own where no pass of this collection makes them first.
  bool reaches_made = make_reaches == nullptr;
  auto make_reaches_alone = [&] {
    if (reaches_made) return;
    const std::size_t n = particles.size();
    for_each_chunk(n, chunks_for_cheap(n),
                   [&](int, std::size_t begin, std::size_t end) { (*make_reaches)(begin, end); });
    reaches_made = true;
  };
  if (!set.always_checked_pairs.empty()) make_reaches_alone();
  auto keep = [&](const Constraint& c, double row_reach) {
    const double gap = evaluate(c, q, box).gap;
    if (gap <= row_reach) out.push_back(c), gap_at_q.push_back(gap);
  };
  // A row's reach: the pair's two particle reaches (a wall row's: twice its particle's),
  // or the one reach for all.
  auto pair_reach = [&](std::int32_t a, std::int32_t b) {
    return particle_reach ? particle_reach[a] + particle_reach[b] : reach;
  };
  if (set.hard_spheres) {
    for (const auto& [a, b] : set.always_checked_pairs) {
      keep(sphere_pair(a, b, particles), pair_reach(a, b));
    }
    bool fresh = anchors_for(list, particles.size()).anchor != nullptr && reach < margin_;
    if (fresh) {
      // The caller's pass made them, or: the reaches, the squares, then, in the same job, the
      // roots as packets (std::sqrt, which may set errno, does not vectorise), chunk by chunk
      // as the step's other passes over the particles (each thread on the particles whose
      // lines it holds); the largest square is exact in any grouping.
      const std::size_t count = anchor_.size();
      const Vec3* anchor = anchor_.data();
      double* moved = moved_.data();
      const double largest2 =
          anchored_largest2
              ? *anchored_largest2
              : ordered_max_around(
                    count, 0.0,
                    [&](std::size_t begin, std::size_t end) {
                      if (!reaches_made) (*make_reaches)(begin, end);
                    },
                    [&](std::size_t i) {
                      moved[i] = norm2(q[i] - anchor[i]);
                      return moved[i];
                    },
                    [&](std::size_t begin, std::size_t end) {
                      const auto length = static_cast<Eigen::Index>(end - begin);
                      Eigen::Map<Eigen::ArrayXd> distance(moved + begin, length);
                      if (particle_reach) {
                        distance = distance.sqrt() +
                                   Eigen::Map<const Eigen::ArrayXd>(particle_reach + begin, length);
                      } else {
                        distance = distance.sqrt();
                      }
                    });
      reaches_made = true;
      // reach + 2 s <= margin, with room for rounding.
      const double room = 0.5 * (margin_ - reach) * (1.0 - 1e-6);
      fresh = largest2 <= room * room;
    }
    if (!fresh) {
      make(set, particles, q, list, box, particle_reach, reaches_made ? nullptr : make_reaches);
      reaches_made = true;
    }
    // With particle reaches, `moved_` holds each particle's displacement plus its reach.
    const double beyond = (particle_reach ? 0.0 : reach) + 1e-9;
    // Each scanned chunk screened on its own thread into its own rows, in chunk order the
    // serial screen's rows in its order on any number of threads. Chunk 0 appends in place;
    // the others' rows are left as `stretches` where their threads wrote them, or else
    // appended after chunk 0's by chunk 1's thread, in the same job (the rows it screened stay
    // on its core, as do the rows of `out` after chunk 0's, which the active set's tests split
    // in two read there; joined by the calling thread, they crossed to its core and back: the
    // 4000-sphere fluid's loop on two threads 0.99x, stop 53; that join itself was 1.7 % of
    // the loop on two threads, stop 63). One
    // scanned chunk (fewer listed pairs than split as cheap items) has its pairs
    // split as cheap items: a pair's screen is a few operations (the 4000-sphere fluid's
    // 12700 pairs took 80 us a call on one thread), and on 2 threads of the loaded 2-core
    // machine a split call took 460 us (the sleeping partner's wake-up), bench/README.md.
    const double* radius = particles.radius.data();
    const bool by_scanned_chunk = scanned_.size() > 1;
    const std::size_t first_count = scanned_[0].pairs.size();
    const std::size_t items = by_scanned_chunk ? scanned_.size() : first_count;
    const int chunks =
        by_scanned_chunk ? static_cast<int>(scanned_.size()) : chunks_for_cheap(first_count);
    if (!by_scanned_chunk) {
      scanned_[0].near.resize(first_count);
      scanned_[0].near_d2.resize(first_count);
    }
    chunk_rows_.resize(static_cast<std::size_t>(chunks));
    chunk_gaps_.resize(static_cast<std::size_t>(chunks));
    auto screen = [&](int c, std::size_t begin, std::size_t end) {
      std::vector<Constraint>& rows = c == 0 ? out : chunk_rows_[static_cast<std::size_t>(c)];
      std::vector<double>& gaps = c == 0 ? gap_at_q : chunk_gaps_[static_cast<std::size_t>(c)];
      if (c != 0) rows.clear(), gaps.clear();
      if (by_scanned_chunk) {
        ScannedChunk& chunk = scanned_[static_cast<std::size_t>(c)];
        chunk.near.resize(chunk.pairs.size());
        chunk.near_d2.resize(chunk.pairs.size());
        screen_pairs(chunk, q, box, radius, reach, particle_reach, exact_below, beyond, 0,
                     chunk.pairs.size(), rows, gaps);
      } else {
        screen_pairs(scanned_[0], q, box, radius, reach, particle_reach, exact_below, beyond, begin,
                     end, rows, gaps);
      }
      if (then && leave_chunks) (*then)(c, rows.data(), gaps.data(), rows.size());
    };
    auto join = [&](int c, std::size_t, std::size_t) {
      if (c != 1) return;
      for (std::size_t k = 1; k < static_cast<std::size_t>(chunks); ++k) {
        out.insert(out.end(), chunk_rows_[k].begin(), chunk_rows_[k].end());
        gap_at_q.insert(gap_at_q.end(), chunk_gaps_[k].begin(), chunk_gaps_[k].end());
      }
    };
    if (leave_chunks) {
      // Nothing to join: no barrier (a round trip between the cores at every call).
      for_each_chunk(items, chunks, screen);
      left_chunks = static_cast<std::size_t>(chunks);
    } else {
      for_each_chunk_then(items, items, chunks, screen, join);
    }
  }
  // The stretches once `out` is complete (its storage no longer moves).
  auto publish = [&] {
    if (!stretches) return;
    stretches->assign(out, gap_at_q);
    for (std::size_t c = 1; c < left_chunks; ++c) stretches->add(chunk_rows_[c], chunk_gaps_[c]);
  };
  // Every wall's rows, wall by wall and particle by particle: the particles tested in chunks,
  // each chunk listing its particles within reach of each wall with their gaps, the rows then
  // kept wall by wall, chunk by chunk (every particle each call: the default input's two walls
  // took 3 % of its loop on two threads when tested on the calling thread alone).
  make_reaches_alone();  // without hard spheres
  if (set.walls.empty()) {
    publish();
    return then && left_chunks > 0;
  }
  const std::size_t n = particles.size();
  const double* radius = particles.radius.data();
  auto row_reach = [particle_reach, reach](std::size_t i) {
    return particle_reach ? 2.0 * particle_reach[i] : reach;
  };
  const int chunks = chunks_for_cheap(n);
  wall_passing_.resize(static_cast<std::size_t>(chunks));
  for_each_chunk(n, chunks, [&](int c, std::size_t begin, std::size_t end) {
    std::vector<std::vector<WallGap>>& passing = wall_passing_[static_cast<std::size_t>(c)];
    passing.resize(set.walls.size());
    for (std::size_t w = 0; w < set.walls.size(); ++w) {
      const Wall& wall = set.walls[w];
      passing[w].clear();
      for (std::size_t i = begin; i < end; ++i) {
        if (wall.kind == ConstraintKind::plane) {
          // evaluate()'s plane gap, without building the row first.
          if (dot(wall.normal, q[i] - wall.point) - radius[i] > row_reach(i)) continue;
        }
        const auto index = static_cast<std::int32_t>(i);
        const double gap = evaluate(set.wall_row(wall, index, radius[i]), q, box).gap;
        if (gap <= row_reach(i)) passing[w].push_back({index, gap});
      }
    }
  });
  for (std::size_t w = 0; w < set.walls.size(); ++w) {
    for (const std::vector<std::vector<WallGap>>& passing : wall_passing_) {
      for (const WallGap& kept : passing[w]) {
        out.push_back(set.wall_row(set.walls[w], kept.particle, radius[kept.particle]));
        gap_at_q.push_back(kept.gap);
      }
    }
  }
  publish();
  return false;
}

// The screen of nearby_inequalities over pairs [first, last), then its exact test
// (evaluate()'s sphere-pair gap, the row built only when kept), appending the kept rows and
// their gaps. The screen may take the separation through the list's shift (no rounding to
// the nearest image): it differs from the minimum image by rounding at most, far inside the
// screen's margin. A pair inside contact + reach by far more than rounding is kept without
// its square root, and its gap is needed only if it may be at most `exact_below`.
void NearbyRows::screen_pairs(ScannedChunk& chunk, const Vec3* q, const Box& box,
                              const double* radius, double reach, const double* particle_reach,
                              double exact_below, double beyond, std::size_t first,
                              std::size_t last, std::vector<Constraint>& out,
                              std::vector<double>& gap_at_q) const {
  const double screen_factor = 1.0 + 1e-6, sure = 1.0 - 1e-6;
  const double infinity = std::numeric_limits<double>::infinity();
  // A row's reach: the pair's two particle reaches, or the one reach for all.
  auto pair_reach = [particle_reach, reach](std::int32_t a, std::int32_t b) {
    return particle_reach ? particle_reach[a] + particle_reach[b] : reach;
  };
  // A pair whose gap at q is certainly beyond the reach (its anchor gap less both
  // displacements exceeds it by far more than rounding) is one the exact test drops too.
  // The others' indices are gathered first without a branch (about a quarter of the pairs
  // pass, unpredictably), then, again without a branch, those within the screen with their
  // squared distances, which are then tested in order; each gathering with its tests first
  // (compact_passing). This chunk's indices go to its own stretch of the chunk's near /
  // near_d2, [first, last).
  const double* moved = moved_.data();
  const Pair* pairs = chunk.pairs.data();
  // The pair's contact distance and shift, as make() took them.
  const bool one_radius = one_radius_;
  const double one_contact = one_contact_;
  auto contact_of = [=](const Pair& pair) {
    return one_radius ? one_contact : radius[pair.a] + radius[pair.b];
  };
  auto shift_of = [this](const Pair& pair) {
    const Vec3& shift = shifts_[pair.code];
    return pair.negated ? -shift : shift;
  };
  std::int32_t* near = chunk.near.data() + first;
  double* near_d2 = chunk.near_d2.data() + first;
  const std::size_t count = compact_passing(
      first, last, 0,
      [&](std::size_t k, std::size_t) {
        const Pair& pair = pairs[k];
        return !(static_cast<double>(pair.anchor_gap) - moved[pair.a] - moved[pair.b] > beyond);
      },
      [&](std::size_t at, std::size_t k, std::size_t) { near[at] = static_cast<std::int32_t>(k); });
  // The second screen in place over near[0, count).
  double d2_of_slot[kCompactBlock];
  auto screen = [&](auto separation2) {
    return compact_passing(
        0, count, 0,
        [&](std::size_t m, std::size_t slot) {
          const Pair& pair = pairs[near[m]];
          const double d2 = separation2(pair);
          const double within = contact_of(pair) + pair_reach(pair.a, pair.b);
          d2_of_slot[slot] = d2;
          return !(d2 > within * within * screen_factor + 1e-300);
        },
        [&](std::size_t at, std::size_t m, std::size_t slot) {
          near[at] = near[m];
          near_d2[at] = d2_of_slot[slot];
        });
  };
  const std::size_t within_count =
      shifted_
          ? screen([&](const Pair& pair) { return norm2(q[pair.a] - q[pair.b] - shift_of(pair)); })
          : screen(
                [&](const Pair& pair) { return norm2(box.minimum_image(q[pair.a] - q[pair.b])); });
  for (std::size_t m = 0; m < within_count; ++m) {
    const Pair& pair = pairs[near[m]];
    const double d2 = near_d2[m];
    const double contact = contact_of(pair);
    const double row_reach = pair_reach(pair.a, pair.b);
    const double within = contact + row_reach;
    const double near_gap = contact + exact_below;
    double gap = infinity;
    if (!(d2 <= within * within * sure) || exact_below < -0.5 * contact ||
        d2 <= near_gap * near_gap * screen_factor + 1e-300) {
      gap = norm(box.minimum_image(q[pair.a] - q[pair.b])) - contact;
      if (!(gap <= row_reach)) continue;
    }
    // sphere_pair(a, b)'s row, made in place (its contact is the pair's).
    Constraint& row = out.emplace_back();
    row.kind = ConstraintKind::sphere_pair;
    row.i = pair.a;
    row.j = pair.b;
    row.length = contact;
    gap_at_q.push_back(gap);
  }
}

}  // namespace deli
