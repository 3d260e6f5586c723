#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/cache_line.hpp"
#include "core/parallel.hpp"
#include "forces/chunk_forces.hpp"
#include "forces/force_term.hpp"
#include "neighbor/neighbor_list.hpp"
#include "pair/pair_evaluator.hpp"
#include "pair/vector_pair_loop.hpp"
#include "system/system.hpp"

namespace deli {

// A pair whose interaction is scaled by a special_bonds factor strictly between 0 and 1;
// such pairs are excluded from the neighbour list and evaluated here.
struct ScaledPair {
  std::int32_t i, j;
  double factor;
};

// The one pair loop: any PairEvaluator (HOOMD-style) becomes a force term. Parameters are a
// dense type x type table.
template <PairEvaluator Evaluator>
class PairForce final : public ForceTerm {
 public:
  using Params = typename Evaluator::Params;

  // shift: every type pair's energy shifted to zero at its cutoff.
  PairForce(std::string name, int type_count, std::vector<Params> table, bool shift,
            double max_cutoff, std::vector<ScaledPair> scaled_pairs)
      : name_(std::move(name)),
        type_count_(type_count),
        table_(std::move(table)),
        max_cutoff_(max_cutoff),
        scaled_pairs_(std::move(scaled_pairs)) {
    for (Params& p : table_) p.energy_shift = shift ? Evaluator::cutoff_energy(p) : 0.0;
  }

  std::string name() const override { return name_; }
  double neighbor_cutoff() const override { return max_cutoff_; }

  // The listed pairs in chunks of particles, as substantial items (each particle's partners
  // scanned against the mask, a block made for each pair it selects): chunk 0 appends to
  // `out`, the others to lists of their own, appended after it in chunk order; then the
  // scaled pairs. The blocks and their order are the serial loop's on any number of threads.
  // Made on the calling thread alone, the shadow-H reflections' blocks were 60 % of the
  // default input's reflections, which then ran as long on two threads as on one.
  bool pair_hessians(const System& system, const NeighborList& neighbors,
                     const std::vector<char>& mask, std::vector<PairHessian>& out) const override {
    // As pieces after out's blocks, then joined.
    flat_pieces_.clear();
    flat_pieces_.last().swap(out);
    pair_hessian_pieces(system, neighbors, mask, flat_pieces_);
    out.swap(flat_pieces_.pieces[0]);
    for (std::size_t k = 1; k < flat_pieces_.used; ++k) {
      out.insert(out.end(), flat_pieces_.pieces[k].begin(), flat_pieces_.pieces[k].end());
    }
    return true;
  }
  // Chunk 0's blocks follow out's last piece's; each later chunk's are a piece of their own,
  // and the scaled pairs' follow in the last.
  bool pair_hessian_pieces(const System& system, const NeighborList& neighbors,
                           const std::vector<char>& mask, PairHessianPieces& out) const override {
    const NeighborList::PartnerRanges ranges = neighbors.partner_ranges();
    const std::size_t n = ranges.particles;
    const int chunks = chunks_for(n);
    // Chunks of particles holding equal numbers of listed pairs, where the list is by particle
    // in order (its ranges follow each other): each pair is tested against the mask. In
    // equal numbers of particles, the default input's lower half (its z axis open, the pairs
    // across the middle listed from below) took 1.28x the upper's time.
    if (n > 0 && ranges.end == ranges.begin + 1) {
      equal_work_starts(ranges.begin, n, chunks, hessian_chunk_starts_);
    } else {
      hessian_chunk_starts_.assign(static_cast<std::size_t>(chunks) + 1, n);
      for (int c = 0; c < chunks; ++c) {
        hessian_chunk_starts_[static_cast<std::size_t>(c)] = chunk_range(n, c, chunks).begin;
      }
    }
    out.last();
    for (int c = 1; c < chunks; ++c) out.add();
    // Chunk c's piece: out.pieces[first + c] (no piece is added during the job).
    const std::size_t first = out.used - static_cast<std::size_t>(chunks);
    // The pairs touching the mask lie where the reflected clusters are, often in one chunk:
    // each chunk finds its own, then, after the job's barrier, makes the blocks of an equal
    // share of them all, in order (made by the chunk that found them, the default input's
    // blocks left the other thread waiting 4.4 us a call).
    chunk_touching_.resize(static_cast<std::size_t>(chunks));
    touching_count_.assign(static_cast<std::size_t>(chunks), OnItsOwnLine<std::size_t>{});
    chunk_ids_.resize(static_cast<std::size_t>(chunks) + 1);
    for (std::size_t c = 0; c <= static_cast<std::size_t>(chunks); ++c) chunk_ids_[c] = c;
    const Vec3* shifts = neighbors.image_shifts().data();
    auto find = [&](int c, std::size_t begin, std::size_t end) {
      const auto k = static_cast<std::size_t>(c);
      touching_count_[k].value = collect_touching(ranges, mask, begin, end, chunk_touching_[k]);
    };
    auto make_blocks = [&](int c, std::size_t, std::size_t) {
      std::size_t total = 0;
      for (const OnItsOwnLine<std::size_t>& count : touching_count_) total += count.value;
      const IndexRange share = chunk_range(total, c, chunks);
      std::size_t start = 0;  // the first pair of chunk k's list among all
      for (std::size_t k = 0; k < static_cast<std::size_t>(chunks) && start < share.end; ++k) {
        const std::size_t count = touching_count_[k].value;
        const std::size_t from = std::max(share.begin, start);
        const std::size_t to = std::min(share.end, start + count);
        if (from < to) {
          append_touching_hessians(system, ranges, shifts,
                                   chunk_touching_[k].data() + (from - start), to - from,
                                   out.pieces[first + static_cast<std::size_t>(c)]);
        }
        start += count;
      }
    };
    for_each_range_then(hessian_chunk_starts_, chunk_ids_, find, make_blocks);
    std::vector<PairHessian>& scaled = out.last();
    for_each_scaled_hessian(system, mask,
                            [&](std::int32_t i, std::int32_t j, const Eigen::Matrix3d& block) {
                              scaled.push_back({i, j, block});
                            });
    return true;
  }

  // v^T H v, pair by pair as (v_i - v_j)^T B (v_i - v_j) for the pair's block B = phi'' u u^T
  // - (f/r) (1 - u u^T) (u the unit separation) in closed form, phi'' (u.w)^2 - (f/r) (|w|^2 -
  // (u.w)^2) with w = v_i - v_j: the blocks' sum to round-off without building them (a third
  // of the operations; the shadow energy of a thermo step was 6 % of the LJ runs). The list's
  // pairs in order, then the scaled pairs. On several threads each chunk of particles sums its
  // listed pairs' terms, the chunk sums are added in chunk order, then the scaled pairs: a sum
  // regrouped as the force loop's energy is (fixed per thread count); one chunk is the serial
  // sum bit for bit.
  bool pair_curvature(const System& system, const NeighborList& neighbors,
                      const std::vector<Vec3>& velocity, double& sum) const override {
    const NeighborList::PartnerRanges ranges = neighbors.partner_ranges();
    const std::size_t n = ranges.particles;
    const int chunks = chunks_for(n);
    if (chunks == 1) {
      sum += listed_curvature(system, ranges, velocity, 0, n);
    } else {
      std::vector<double> partial(static_cast<std::size_t>(chunks), 0.0);
      for_each_fixed_chunk(n, chunks, [&](int c, std::size_t begin, std::size_t end) {
        partial[static_cast<std::size_t>(c)] =
            listed_curvature(system, ranges, velocity, begin, end);
      });
      for (const double p : partial) sum += p;
    }
    for (const ScaledPair& pair : scaled_pairs_) {
      sum += curvature_term(system, velocity, pair.i, pair.j, pair.factor);
    }
    return true;
  }

  double compute(const System& system, const NeighborList& neighbors, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally) const override {
    return compute(system, neighbors, force, virial, tally, false);
  }
  // The vector loop writes each particle's force once: in place of the zeroing pass. Its sums
  // start from +0 and so are never -0: the same bits as zeroing, then adding.
  double compute_overwriting(const System& system, const NeighborList& neighbors,
                             std::vector<Vec3>& force, SymTensor& virial,
                             bool tally) const override {
    if (!vector_loop_applies(neighbors.coded()) || system.particles.size() == 0) {
      return ForceTerm::compute_overwriting(system, neighbors, force, virial, tally);
    }
    return compute(system, neighbors, force, virial, tally, true);
  }

 private:
  // `overwrite` (the vector loop only): its forces replace force's contents.
  double compute(const System& system, const NeighborList& neighbors, std::vector<Vec3>& force,
                 SymTensor& virial, bool tally, bool overwrite) const {
    const std::size_t n = system.particles.size();
    const NeighborList::CellOrdered& ordered = neighbors.cell_ordered();
    const bool by_slot = ordered.particle.size() == n && n > 0;
    // The list read where the build left it, by slot (partners as slots) or by particle
    // through the ranges: the list by particle is not made for these loops.
    const NeighborList::PartnerRanges ranges =
        by_slot ? ordered.ranges() : neighbors.partner_ranges();
    double energy = 0.0;
    if (vector_loop_applies(neighbors.coded()) && n > 0) {
      energy = vector_loops(system.particles.position, by_slot ? ordered.particle.data() : nullptr,
                            ranges, neighbors, force, virial, tally, overwrite);
    } else if (!by_slot) {
      const Listed listed{system.particles.position.data(), system.particles.type.data(), ranges,
                          neighbors.coded()};
      energy = loops(system.box, neighbors, listed, n, force, virial, tally);
    } else {
      // Cache order: positions and types gathered into the list's cell order, the forces
      // found there added back by particle.
      const std::int32_t* particle = ordered.particle.data();
      ordered_position_.resize(n);
      ordered_type_.resize(n);
      ordered_force_.resize(n);
      const Vec3* x = system.particles.position.data();
      const int* type = system.particles.type.data();
      parallel_for(n, [&](std::size_t s) {
        ordered_position_[s] = x[particle[s]];
        ordered_type_[s] = type[particle[s]];
        ordered_force_[s] = Vec3{};
      });
      const Listed listed{ordered_position_.data(), ordered_type_.data(), ranges,
                          neighbors.coded()};
      energy = loops(system.box, neighbors, listed, n, ordered_force_, virial, tally);
      parallel_for(n, [&](std::size_t s) { force[particle[s]] += ordered_force_[s]; });
    }
    return energy + (tally ? scaled_pairs<true>(system, force, virial)
                           : scaled_pairs<false>(system, force, virial));
  }

  // The Hessian block of every listed pair in reach touching a masked particle (all with an
  // empty mask), in list order (pair_hessian_pieces; the scaled pairs' follow). In three passes, as
  // the scalar force loop: the pairs touching the mask, those of them in reach, then their blocks,
  // each pass without a branch per pair. A mask holds a few reflected clusters (the default input:
  // 60 of 1200 particles, 2200 of 48000 listed pairs a call), so a branch on each pair's mask, then
  // on its reach, was mispredicted often enough to take a third of this loop (stop 50, the default
  // input: reflections phase 0.76 and loop 0.91 on one thread, 0.72 and 0.80 on two); the blocks'
  // pass then in vectors: 0.95 and 0.98 on one thread, 0.84 and 0.88 on two. The same operations on
  // each pair: the same blocks (Threads.MaskedPairHessiansOnTwoThreadsAreTheOneThreadBlocks).
  struct Touching {
    std::int32_t i;
    std::uint32_t k;  // the pair's entry in the list (under 2^32: 16 GB of partners)
  };
  // The first pass: the listed pairs of particles begin..end-1 touching a masked particle, in
  // list order, into `touching` (grown, never cut); returns their count.
  static std::size_t collect_touching(const NeighborList::PartnerRanges& ranges,
                                      const std::vector<char>& mask, std::size_t begin,
                                      std::size_t end, std::vector<Touching>& touching) {
    std::size_t count = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t first = ranges.begin[i], last = ranges.end[i];
      if (touching.size() < count + (last - first)) touching.resize(2 * (count + last - first));
      const auto ii = static_cast<std::int32_t>(i);
      if (mask.empty() || mask[i]) {
        for (std::size_t k = first; k < last; ++k) {
          touching[count++] = {ii, static_cast<std::uint32_t>(k)};
        }
      } else {
        for (std::size_t k = first; k < last; ++k) {
          touching[count] = {ii, static_cast<std::uint32_t>(k)};
          count += mask[static_cast<std::size_t>(ranges.neighbors[k])] != 0;
        }
      }
    }
    return count;
  }
  // The later passes: of the `count` pairs at `touching`, those in reach, then their blocks,
  // appended to `to` in order.
  void append_touching_hessians(const System& system, const NeighborList::PartnerRanges& ranges,
                                const Vec3* shifts, const Touching* touching, std::size_t count,
                                std::vector<PairHessian>& to) const {
    // The pairs in reach, by component (so that the blocks' pass runs in vectors).
    struct InReach {
      std::vector<std::int32_t> i, j;
      std::vector<double> dx, dy, dz, r2;
      std::vector<std::size_t> params;
      // The blocks' upper triangles (pair_hessian_upper).
      std::vector<double> xx, xy, xz, yy, yz, zz;
      void resize(std::size_t n) {
        for (auto* v : {&i, &j}) v->resize(n);
        for (auto* v : {&dx, &dy, &dz, &r2, &xx, &xy, &xz, &yy, &yz, &zz}) v->resize(n);
        params.resize(n);
      }
    };
    thread_local InReach in_reach;
    const std::vector<Vec3>& x = system.particles.position;
    const std::vector<int>& type = system.particles.type;
    InReach& q = in_reach;
    if (q.r2.size() < count) q.resize(count);
    std::size_t kept = 0;
    auto keep_in_reach = [&](auto separation) {
      for (std::size_t k = 0; k < count; ++k) {
        const Touching t = touching[k];
        const std::int32_t j = ranges.neighbors[t.k];
        const Vec3 d = separation(t.i, j, t.k);
        const double r2 = norm2(d);
        const auto params = static_cast<std::size_t>(type[t.i] * type_count_ + type[j]);
        q.i[kept] = t.i, q.j[kept] = j, q.dx[kept] = d.x, q.dy[kept] = d.y, q.dz[kept] = d.z;
        q.r2[kept] = r2, q.params[kept] = params;
        kept += !(r2 >= table_[params].cutoff2);  // as visit_hessian: a NaN r2 kept
      }
    };
    // With image codes, x_i - x_j - shift: the minimum image's bits (the shift is the
    // rounding's multiple of the period) without minimum_image()'s rounding, which g++ makes
    // a branch per axis (the default input, one thread: this function 0.81x its samples).
    if (const std::uint8_t* codes = ranges.image_codes) {
      keep_in_reach([&](std::int32_t i, std::int32_t j, std::uint32_t k) {
        return x[i] - x[j] - shifts[codes[k]];
      });
    } else {
      const Box& box = system.box;
      keep_in_reach([&](std::int32_t i, std::int32_t j, std::uint32_t) {
        return box.minimum_image(x[i] - x[j]);
      });
    }
    // pair_hessian_upper on each pair: pair_hessian_block's bits. Through restrict pointers:
    // the compiler then needs no test of the arrays' overlap to run the loop in vectors.
    auto blocks = [kept](auto params_of, const double* __restrict r2s, const double* __restrict dxs,
                         const double* __restrict dys, const double* __restrict dzs,
                         double* __restrict xx, double* __restrict xy, double* __restrict xz,
                         double* __restrict yy, double* __restrict yz, double* __restrict zz) {
      for (std::size_t k = 0; k < kept; ++k) {
        const Params& p = params_of(k);
        const double r2 = r2s[k];
        double f_over_r, e;
        Evaluator::evaluate(p, r2, f_over_r, e);
        const PairHessianUpper b = pair_hessian_upper(dxs[k], dys[k], dzs[k], r2, f_over_r,
                                                      Evaluator::second_derivative(p, r2));
        xx[k] = b.xx, xy[k] = b.xy, xz[k] = b.xz, yy[k] = b.yy, yz[k] = b.yz, zz[k] = b.zz;
      }
    };
    auto run_blocks = [&](auto params_of) {
      blocks(params_of, q.r2.data(), q.dx.data(), q.dy.data(), q.dz.data(), q.xx.data(),
             q.xy.data(), q.xz.data(), q.yy.data(), q.yz.data(), q.zz.data());
    };
    if (type_count_ == 1) {
      const Params one = table_[0];
      run_blocks([one](std::size_t) -> const Params& { return one; });
    } else {
      const std::size_t* params = q.params.data();
      const Params* table = table_.data();
      run_blocks([params, table](std::size_t k) -> const Params& { return table[params[k]]; });
    }
    // Written in place (a block made, then copied in by push_back, took 17 cycles a pair).
    const std::size_t base = to.size();
    to.resize(base + kept);
    PairHessian* out = to.data() + base;
    for (std::size_t k = 0; k < kept; ++k) {
      PairHessian& h = out[k];
      h.a = q.i[k], h.b = q.j[k];
      double* b = h.block.data();  // column-major; the block is symmetric
      b[0] = q.xx[k], b[1] = q.xy[k], b[2] = q.xz[k];
      b[3] = q.xy[k], b[4] = q.yy[k], b[5] = q.yz[k];
      b[6] = q.xz[k], b[7] = q.yz[k], b[8] = q.zz[k];
    }
  }
  template <class Visit>
  void for_each_scaled_hessian(const System& system, const std::vector<char>& mask,
                               Visit&& visit) const {
    for (const ScaledPair& s : scaled_pairs_) {
      if (!mask.empty() && !mask[s.i] && !mask[s.j]) continue;
      visit_hessian(system, s.i, s.j, s.factor, visit);
    }
  }
  // The listed pairs of particles begin..end-1: their curvature terms summed in list order.
  double listed_curvature(const System& system, const NeighborList::PartnerRanges& ranges,
                          const std::vector<Vec3>& velocity, std::size_t begin,
                          std::size_t end) const {
    if constexpr (VectorCurvatureEvaluator<Evaluator>) {
      if (type_count_ == 1 && Evaluator::curvature_loop_built()) {
        const CurvatureChunk chunk{system.particles.position.data(),
                                   velocity.data(),
                                   ranges.neighbors,
                                   ranges.begin,
                                   system.box.period(),
                                   system.box.inverse_period(),
                                   begin,
                                   end,
                                   ranges.end};
        return Evaluator::curvature_loop(table_[0], chunk);
      }
    }
    double sum = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
      for (std::size_t k = ranges.begin[i]; k < ranges.end[i]; ++k) {
        sum += curvature_term(system, velocity, static_cast<std::int32_t>(i), ranges.neighbors[k],
                              1.0);
      }
    }
    return sum;
  }
  // (v_i - v_j)^T B (v_i - v_j) for the pair's block scaled by `factor`; 0 out of reach.
  double curvature_term(const System& system, const std::vector<Vec3>& velocity, std::int32_t i,
                        std::int32_t j, double factor) const {
    const std::vector<Vec3>& x = system.particles.position;
    const std::vector<int>& type = system.particles.type;
    const Vec3 d = system.box.minimum_image(x[i] - x[j]);
    const double r2 = norm2(d);
    const Params& p = table_[static_cast<std::size_t>(type[i] * type_count_ + type[j])];
    if (r2 >= p.cutoff2) return 0.0;
    double f_over_r, e;
    Evaluator::evaluate(p, r2, f_over_r, e);
    const Vec3 w = velocity[i] - velocity[j];
    const double along = dot(d, w);
    const double along2 = along * along / r2;
    return factor * (Evaluator::second_derivative(p, r2) * along2 - f_over_r * (norm2(w) - along2));
  }
  // visit(i, j, block) with the pair's block scaled by `factor`, when the pair is in reach.
  template <class Visit>
  void visit_hessian(const System& system, std::int32_t i, std::int32_t j, double factor,
                     Visit&& visit) const {
    const std::vector<Vec3>& x = system.particles.position;
    const std::vector<int>& type = system.particles.type;
    const Vec3 d = system.box.minimum_image(x[i] - x[j]);
    const double r2 = norm2(d);
    const Params& p = table_[static_cast<std::size_t>(type[i] * type_count_ + type[j])];
    if (r2 >= p.cutoff2) return;
    double f_over_r, e;
    Evaluator::evaluate(p, r2, f_over_r, e);
    const Eigen::Matrix3d block =
        factor * pair_hessian_block(d, r2, f_over_r, Evaluator::second_derivative(p, r2));
    visit(i, j, block);
  }

  // The particles' positions and types and their listed partners, in the list's order:
  // by particle, or by slot in cell order (partners and positions by slot).
  struct Listed {
    const Vec3* x;
    const int* type;
    NeighborList::PartnerRanges partners;
    bool coded;  // periodic shifts from image codes (else minimum-image rounding)
  };

  // The evaluator's vector loop (in a build without its instruction set, its sums one pair
  // at a time: the same bits in every build): one type (one parameter set) and image-coded
  // lists; else the scalar loop.
  bool vector_loop_applies(bool coded) const {
    if constexpr (VectorPairEvaluator<Evaluator>) {
      return type_count_ == 1 && coded;
    }
    return false;
  }

  // The vector loop over the list by slot: positions gathered into slot order (slot s holds
  // particle[s], or particle s without `particle`) padded to four doubles, the forces found
  // there added back by particle (written, with `overwrite`). Slot s's partners are its range
  // in `partners`. On several threads, touched_vector_loops().
  double vector_loops(const std::vector<Vec3>& x, const std::int32_t* particle,
                      const NeighborList::PartnerRanges& partners, const NeighborList& neighbors,
                      std::vector<Vec3>& force, SymTensor& virial, bool tally,
                      bool overwrite) const {
    if constexpr (VectorPairEvaluator<Evaluator>) {
      const std::size_t n = x.size();
      const int chunks = chunks_for(n);
      if (chunks > 1) {
        return touched_vector_loops(x, particle, partners, neighbors, force, virial, tally, chunks,
                                    overwrite);
      }
      auto at = [particle](std::size_t s) { return particle ? particle[s] : s; };
      padded_positions_.resize(1);
      std::vector<PaddedVec3>& position = padded_positions_[0];
      position.resize(n);
      for (std::size_t s = 0; s < n; ++s) {
        const Vec3& p = x[at(s)];
        position[s] = {p.x, p.y, p.z, 0.0};
      }
      padded_force_.assign(n, PaddedVec3{});
      const double energy =
          Evaluator::vector_loop(table_[0],
                                 vector_chunk(position.data(), padded_force_.data(), partners,
                                              neighbors.image_shifts().data(), 0, n),
                                 tally, virial);
      for (std::size_t s = 0; s < n; ++s) {
        store_force(force[at(s)], padded_force_[s], overwrite);
      }
      return energy;
    }
    return 0.0;
  }

  // A slot's padded force sum into its particle's force: written with `overwrite`, else added.
  static void store_force(Vec3& to, const PaddedVec3& f, bool overwrite) {
    const Vec3 sum{f.x, f.y, f.z};
    to = overwrite ? sum : to + sum;
  }

  // Slots [begin, end) of the list `partners` for the vector loop, on positions x by slot.
  static VectorPairChunk vector_chunk(const PaddedVec3* x, PaddedVec3* f,
                                      const NeighborList::PartnerRanges& partners,
                                      const Vec3* shifts, std::size_t begin, std::size_t end) {
    return {x,
            f,
            partners.neighbors,
            partners.image_codes,
            partners.begin,
            shifts,
            static_cast<std::int32_t>(begin),
            static_cast<std::int32_t>(end),
            partners.end};
  }

  // vector_loops() on several chunks of slots, each with positions and forces of its own on
  // the blocks it touches (TouchedBlocks): gathered and zeroed there by its thread, then, in
  // the same job of the team, each chunk's slots' forces added up over the chunks in chunk
  // order (a chunk that touches no slot of a block adds nothing there) and added to `force`.
  // Energies and virials are summed in chunk order, as ChunkedForceLoopOf sums them.
  // A chunk's partners' positions, read in no order, are then in its own core's cache, copied
  // there in one stream: read from a copy another core wrote, each line missed cost a round
  // trip between the cores (about 500 ns on the 2-core machine of bench/README.md), and LJ
  // 4000's pair loop took as long on two threads as on one. Each chunk once copied every
  // position and made a whole force buffer, added up by the calling thread alone after the
  // job where the particle passes are not split (cheap_chunk_minimum()); copying and
  // adding only the touched blocks, in the job, took LJ 4000's pair phase on two threads to
  // 0.97x, the Kremer-Grest melt's (inputs/lj_chains/melt.toml) to 0.89x, the rigid melt's to
  // 0.99x, the default input's to 1.00x (bench/README.md, "Stop 47"). The chunks hold equal
  // numbers of listed pairs (NeighborList::pair_chunk_starts): in equal numbers of slots, the
  // default input's lower half (its z axis open, the pairs across the middle listed from
  // below) held a quarter more pairs than the upper; its pair phase on two threads 0.94x.
  double touched_vector_loops(const std::vector<Vec3>& x, const std::int32_t* particle,
                              const NeighborList::PartnerRanges& partners,
                              const NeighborList& neighbors, std::vector<Vec3>& force,
                              SymTensor& virial, bool tally, int chunks, bool overwrite) const {
    const std::size_t n = x.size();
    auto at = [particle](std::size_t s) { return particle ? particle[s] : s; };
    const auto slots = static_cast<std::size_t>(chunks);
    padded_positions_.resize(slots);
    padded_forces_.resize(slots);
    chunk_sources_.resize(slots);
    for (std::vector<const PaddedVec3*>& from : chunk_sources_) from.resize(slots);
    chunk_virials_.assign(slots, SymTensor{});
    chunk_energies_.assign(slots, 0.0);
    const TouchedBlocks& touched = neighbors.touched_blocks(chunks);
    const Vec3* shifts = neighbors.image_shifts().data();
    auto chunk_loop = [&](int c, std::size_t begin, std::size_t end) {
      const auto k = static_cast<std::size_t>(c);
      std::vector<PaddedVec3>& position = padded_positions_[k];
      std::vector<PaddedVec3>& f = padded_forces_[k];
      position.resize(n);
      f.resize(n);
      for (const TouchedBlocks::Run& run : touched.runs(c)) {
        for (std::size_t s = run.begin; s < run.end; ++s) {
          const Vec3& p = x[at(s)];
          position[s] = {p.x, p.y, p.z, 0.0};
        }
        std::fill(f.begin() + static_cast<std::ptrdiff_t>(run.begin),
                  f.begin() + static_cast<std::ptrdiff_t>(run.end), PaddedVec3{});
      }
      chunk_energies_[k] = Evaluator::vector_loop(
          table_[0], vector_chunk(position.data(), f.data(), partners, shifts, begin, end), tally,
          chunk_virials_[k]);
    };
    // Block by block: the chunks touching the block, then its slots' sums over them.
    auto add = [&](int chunk, std::size_t begin, std::size_t end) {
      std::vector<const PaddedVec3*>& from = chunk_sources_[static_cast<std::size_t>(chunk)];
      for (std::size_t first = begin; first < end;) {
        const std::size_t block = TouchedBlocks::block_of(first);
        const std::size_t last = std::min(end, TouchedBlocks::block_begin(block + 1));
        std::size_t count = 0;
        for (int c = 0; c < chunks; ++c) {
          if (touched.touches(c, block)) {
            from[count++] = padded_forces_[static_cast<std::size_t>(c)].data();
          }
        }
        for (std::size_t s = first; count > 0 && s < last; ++s) {
          PaddedVec3 sum = from[0][s];
          for (std::size_t t = 1; t < count; ++t) sum += from[t][s];
          store_force(force[at(s)], sum, overwrite);
        }
        // A block no chunk touches (none: a chunk touches its own) has no forces.
        for (std::size_t s = first; count == 0 && overwrite && s < last; ++s) force[at(s)] = Vec3{};
        first = last;
      }
    };
    // Equal chunks of pairs (the list's, kept for its build with the touched blocks), whatever
    // the threads' speeds: each slot's force adds the chunks' in chunk order.
    const std::vector<std::size_t>& starts = neighbors.pair_chunk_starts(chunks);
    {
      const UnbalancedJobs unmeasured;
      for_each_range_then(starts, starts, chunk_loop, add);
    }
    // Chunk 0's virial was the caller's own in ChunkedForceLoopOf: added first, then the
    // others in order.
    virial += chunk_virials_[0];
    double energy = chunk_energies_[0];
    for (std::size_t c = 1; c < slots; ++c) {
      energy += chunk_energies_[c];
      virial += chunk_virials_[c];
    }
    return energy;
  }

  // Chunks of consecutive particles (slots), each with its listed pairs.
  double loops(const Box& box, const NeighborList& neighbors, const Listed& listed, std::size_t n,
               std::vector<Vec3>& force, SymTensor& virial, bool tally) const {
    const Vec3* shifts = neighbors.image_shifts().data();
    return chunked_.run(
        n, force, virial, [&](std::size_t begin, std::size_t end, Vec3* f, SymTensor& w) {
          const auto first = static_cast<std::int32_t>(begin);
          const auto last = static_cast<std::int32_t>(end);
          if (tally) {
            return listed.coded ? loop<true, true>(box, listed, shifts, first, last, f, w)
                                : loop<true, false>(box, listed, shifts, first, last, f, w);
          }
          return listed.coded ? loop<false, true>(box, listed, shifts, first, last, f, w)
                              : loop<false, false>(box, listed, shifts, first, last, f, w);
        });
  }

  // Particles first..last-1 with their listed partners: forces added to f, the virial to
  // `virial`; returns the energy. kTally: accumulate energy and virial. kCoded: periodic
  // shifts from the list's image codes instead of minimum-image rounding.
  template <bool kTally, bool kCoded>
  double loop(const Box& box, const Listed& listed, const Vec3* shifts, std::int32_t first,
              std::int32_t last, Vec3* f, SymTensor& virial) const {
    const Vec3* x = listed.x;
    const int* type = listed.type;
    const Vec3 period = box.period(), inverse = box.inverse_period();
    const std::int32_t* list = listed.partners.neighbors;
    const std::uint8_t* codes = listed.partners.image_codes;
    const std::size_t* begin = listed.partners.begin;
    const std::size_t* end = listed.partners.end;

    double energy = 0.0;
    SymTensor w;
    // Two passes per particle: separations of all listed partners, compacted without a
    // branch to those inside their cutoff (a branch the predictor loses for about half the
    // pairs), then the potential on those alone.
    struct Inside {
      std::int32_t j;
      double dx, dy, dz, r2;
    };
    thread_local std::vector<Inside> inside;
    for (std::int32_t i = first; i < last; ++i) {
      const Vec3 xi = x[i];
      const Params* row = &table_[static_cast<std::size_t>(type[i] * type_count_)];
      const std::size_t count = end[i] - begin[i];
      if (inside.size() < count + 1) inside.resize(2 * count + 1);
      std::size_t kept = 0;
      for (std::size_t k = begin[i]; k < end[i]; ++k) {
        const std::int32_t j = list[k];
        double dx = xi.x - x[j].x, dy = xi.y - x[j].y, dz = xi.z - x[j].z;
        if constexpr (kCoded) {
          const Vec3& s = shifts[codes[k]];
          dx -= s.x, dy -= s.y, dz -= s.z;
        } else {
          dx -= period.x * Box::round_to_integer(dx * inverse.x);
          dy -= period.y * Box::round_to_integer(dy * inverse.y);
          dz -= period.z * Box::round_to_integer(dz * inverse.z);
        }
        const double r2 = dx * dx + dy * dy + dz * dz;
        inside[kept] = {j, dx, dy, dz, r2};
        kept += r2 < row[type[j]].cutoff2;
      }
      Vec3 fi;
      for (std::size_t k = 0; k < kept; ++k) {
        const Inside& q = inside[k];
        const Params& p = row[type[q.j]];
        double f_over_r, e;
        Evaluator::evaluate(p, q.r2, f_over_r, e);
        const double fx = q.dx * f_over_r, fy = q.dy * f_over_r, fz = q.dz * f_over_r;
        fi.x += fx, fi.y += fy, fi.z += fz;
        f[q.j].x -= fx, f[q.j].y -= fy, f[q.j].z -= fz;
        if constexpr (kTally) {
          energy += e - p.energy_shift;
          w.xx += q.dx * fx, w.yy += q.dy * fy, w.zz += q.dz * fz;
          w.xy += q.dx * fy, w.xz += q.dx * fz, w.yz += q.dy * fz;
        }
      }
      f[i] += fi;
    }
    if constexpr (kTally) virial += w;
    return energy;
  }

  // The special pairs (scaled, outside the list); energy and virial only when tallied.
  template <bool Tally>
  double scaled_pairs(const System& system, std::vector<Vec3>& force, SymTensor& virial) const {
    const std::vector<Vec3>& x = system.particles.position;
    const std::vector<int>& type = system.particles.type;
    double energy = 0.0;
    for (const ScaledPair& s : scaled_pairs_) {
      const Vec3 d = system.box.minimum_image(x[s.i] - x[s.j]);
      const double r2 = norm2(d);
      const Params& p = table_[static_cast<std::size_t>(type[s.i] * type_count_ + type[s.j])];
      if (r2 >= p.cutoff2) continue;
      double f_over_r, e;
      Evaluator::evaluate(p, r2, f_over_r, e);
      const Vec3 fs = d * (s.factor * f_over_r);
      force[s.i] += fs;
      force[s.j] -= fs;
      if constexpr (Tally) {
        energy += s.factor * (e - p.energy_shift);
        virial.add_outer(d, fs);
      }
    }
    return energy;
  }

  std::string name_;
  int type_count_;
  std::vector<Params> table_;
  double max_cutoff_;
  std::vector<ScaledPair> scaled_pairs_;
  // Scratch of compute():
  mutable ChunkedForceLoop chunked_;
  mutable std::vector<Vec3> ordered_position_, ordered_force_;  // cache order, by slot
  mutable std::vector<int> ordered_type_;
  mutable std::vector<std::vector<PaddedVec3>> padded_positions_;  // one per chunk
  mutable std::vector<PaddedVec3> padded_force_;                   // one chunk's
  // touched_vector_loops()'s, one per chunk:
  mutable std::vector<std::vector<PaddedVec3>> padded_forces_;
  mutable std::vector<std::vector<const PaddedVec3*>> chunk_sources_;  // a block's summed chunks
  mutable std::vector<SymTensor> chunk_virials_;
  mutable std::vector<double> chunk_energies_;
  // pair_hessian_pieces()' chunks: the pairs each found,
  mutable std::vector<std::vector<Touching>> chunk_touching_;
  mutable std::vector<OnItsOwnLine<std::size_t>> touching_count_;  // how many,
  mutable std::vector<std::size_t> chunk_ids_;                     // and 0, 1, ... chunks
  mutable PairHessianPieces flat_pieces_;                          // pair_hessians()' pieces
  mutable std::vector<std::size_t> hessian_chunk_starts_;          // and where they start
};

}  // namespace deli
