#include "neighbor/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>

#include "core/parallel.hpp"
#include "neighbor/candidate_scan.hpp"

namespace deli {

namespace {
// Cells along x per reach in the grid of rows (make_grid).
constexpr int kRowCells = 8;
// Image code of a shift of (kx, ky, kz) periods, each in -1..1.
constexpr int code_of(int kx, int ky, int kz) {
  return (kx + 1) + 3 * (ky + 1) + 9 * (kz + 1);
}
constexpr int kNoShift = code_of(0, 0, 0);
}  // namespace

NeighborList::NeighborList(double cutoff, double skin) : cutoff_(cutoff), skin_(skin) {}

void NeighborList::set_exclusions(std::vector<std::array<std::int32_t, 2>> excluded) {
  for (auto& pair : excluded) {
    if (pair[0] > pair[1]) std::swap(pair[0], pair[1]);
  }
  std::sort(excluded.begin(), excluded.end());
  excluded.erase(std::unique(excluded.begin(), excluded.end()), excluded.end());
  excluded_ = std::move(excluded);
  excluded_offsets_.clear();
  position_at_build_.clear();  // force a rebuild
}

// Cells a reach wide along y and z and an eighth of one along x: a particle scans four rows
// of cells along x (half the 3 x 3 rows around its own, each row 2 + 1/8 reaches long) and
// the later part of its own row. A row is one run of slots (the cells along x are consecutive),
// and a run costs about as much as a dozen candidates (below): cells half a reach wide along
// every axis scan half the volume of cells a reach wide over twelve rows rather than four,
// and took as long (LJ 32000, list phase 0.153 and 0.150-0.162 s per 100 steps); these rows
// took 0.129 s (0.127 with a twelfth of a reach along x, 0.131 with a sixth; 6 rounds each,
// one thread, bench/README.md, "Stop 46"). Boxes under three reaches along y or z fall back to
// cells half a reach wide, small periodic boxes to cells a reach wide and, below three cells
// along a periodic axis, to minimum-image separations over the distinct neighbouring cells;
// dilute systems, whose fine cells would outnumber the particles, to cells a reach wide.
// Open axes span the particles' extent.
NeighborList::Grid NeighborList::make_grid(const std::vector<Vec3>& inside, const Box& box) const {
  const double reach = cutoff_ + skin_;
  Vec3 lo, extent;
  for (int a = 0; a < 3; ++a) {
    lo[a] = box.lo()[a];
    extent[a] = box.length()[a];
    if (!box.periodic(a)) {
      double lo_p = box.lo()[a], hi_p = box.hi()[a];
      for (const Vec3& x : inside) lo_p = std::min(lo_p, x[a]), hi_p = std::max(hi_p, x[a]);
      lo[a] = lo_p, extent[a] = hi_p - lo_p;
    }
  }
  bool coarsened = false;
  auto grid_with = [&](std::array<double, 3> width, std::array<int, 3> span) {
    Grid g;
    g.span = span;
    for (int a = 0; a < 3; ++a) {
      g.count[a] = std::max(1, static_cast<int>(std::min(extent[a] / width[a], 1024.0)));
    }
    // A sparse or spread-out system would get more cells than particles: coarser cells
    // (never narrower than `width`) keep memory proportional to the particle count.
    const double limit = std::max(125.0, 2.0 * static_cast<double>(inside.size()));
    coarsened = false;
    while (static_cast<double>(g.count[0]) * g.count[1] * g.count[2] > limit) {
      for (int& c : g.count) c = (c + 1) / 2;
      coarsened = true;
    }
    for (int a = 0; a < 3; ++a) {
      g.origin[a] = lo[a];
      g.inverse_width[a] = g.count[a] / std::max(extent[a], 1e-300);
      if (box.periodic(a) && g.count[a] < 2 * span[a] + 1) g.shifted = false;
    }
    return g;
  };
  const Grid rows = grid_with({reach / kRowCells, reach, reach}, {kRowCells, 1, 1});
  if (rows.shifted && !coarsened) return rows;
  const Grid fine = grid_with({reach / 2, reach / 2, reach / 2}, {2, 2, 2});
  if (fine.shifted && !coarsened) return fine;
  // Coarsened half-reach cells are about a reach wide, yet scanned over the 5^3 stencil:
  // cells a reach wide over a 3^3 stencil scan a fifth of the volume (a dilute hard-sphere
  // fluid, whose reach is about one diameter).
  const Grid full = grid_with({reach, reach, reach}, {1, 1, 1});
  if (fine.shifted && !full.shifted) return fine;
  return full;
}

void NeighborList::make_stencils(const Grid& grid, const Box& box) {
  const int cells = grid.count[0] * grid.count[1] * grid.count[2];
  stencil_offsets_.assign(1, 0);
  stencil_cells_.clear();
  stencil_ends_.clear();
  stencil_codes_.clear();
  std::vector<std::pair<std::int32_t, std::uint8_t>> around;
  for (int c = 0; c < cells; ++c) {
    const int home[3] = {c % grid.count[0], (c / grid.count[0]) % grid.count[1],
                         c / (grid.count[0] * grid.count[1])};
    around.clear();
    const std::array<int, 3> s = grid.span;
    for (int dz = -s[2]; dz <= s[2]; ++dz)
      for (int dy = -s[1]; dy <= s[1]; ++dy)
        for (int dx = -s[0]; dx <= s[0]; ++dx) {
          // Half stencil: of the offsets +o and -o only the lexicographically positive
          // one, so each pair of distinct cells is met once; the home cell is scanned apart.
          if (grid.shifted && (dz < 0 || (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0))))) continue;
          int k[3] = {home[0] + dx, home[1] + dy, home[2] + dz};
          int wraps[3] = {0, 0, 0};
          bool inside_grid = true;
          for (int a = 0; a < 3; ++a) {
            if (k[a] >= 0 && k[a] < grid.count[a]) continue;
            if (!box.periodic(a)) {
              inside_grid = false;
              break;
            }
            wraps[a] = k[a] < 0 ? -1 : 1;
            k[a] = ((k[a] % grid.count[a]) + grid.count[a]) % grid.count[a];
          }
          if (!inside_grid) continue;
          const int cell = (k[2] * grid.count[1] + k[1]) * grid.count[0] + k[0];
          around.emplace_back(cell,
                              grid.shifted ? code_of(wraps[0], wraps[1], wraps[2]) : kNoShift);
        }
    if (grid.shifted && std::any_of(around.begin(), around.end(),
                                    [](const auto& a) { return a.second != kNoShift; })) {
      // The unshifted cells first, then those through each periodic shift together (by
      // code): a particle's partners through one shift are consecutive in its list, and a
      // vector pair loop's vectors of partners mostly have one shift or none (the AVX2 LJ
      // loop alone on a 32000-atom liquid: 0.95x, with its shift broadcast 0.93x).
      auto order = [](std::uint8_t code) { return code == kNoShift ? -1 : int{code}; };
      std::stable_sort(around.begin(), around.end(), [&](const auto& l, const auto& r) {
        return order(l.second) < order(r.second);
      });
    }
    if (!grid.shifted) {
      // Several offsets can land on one cell: keep each once.
      std::sort(around.begin(), around.end());
      around.erase(std::unique(around.begin(), around.end(),
                               [](const auto& l, const auto& r) { return l.first == r.first; }),
                   around.end());
    }
    // Neighbouring cells adjacent in memory (consecutive along x, through the same shift)
    // are scanned as one run of slots: the same candidates in the same order, with fewer
    // short loops, whose trip counts (a cell holds a particle or two in a dilute fluid)
    // the branch predictor mostly loses.
    const std::size_t first_run = stencil_cells_.size();
    for (const auto& [cell, code] : around) {
      if (stencil_cells_.size() > first_run && stencil_ends_.back() == cell &&
          stencil_codes_.back() == code) {
        ++stencil_ends_.back();
        continue;
      }
      stencil_cells_.push_back(cell);
      stencil_ends_.push_back(cell + 1);
      stencil_codes_.push_back(code);
    }
    stencil_offsets_.push_back(stencil_cells_.size());
  }
  stencil_grid_ = grid;
  stencil_periodic_ = {box.periodic(0), box.periodic(1), box.periodic(2)};
}

NeighborList::Stencils NeighborList::take_stencils() {
  Stencils stencils{stencil_grid_,
                    stencil_periodic_,
                    std::move(stencil_offsets_),
                    std::move(stencil_cells_),
                    std::move(stencil_ends_),
                    std::move(stencil_codes_)};
  stencil_offsets_.clear();  // none: the next build makes them
  stencil_cells_.clear();
  stencil_ends_.clear();
  stencil_codes_.clear();
  return stencils;
}

void NeighborList::adopt_stencils(Stencils stencils) {
  stencil_grid_ = stencils.grid;
  stencil_periodic_ = stencils.periodic;
  stencil_offsets_ = std::move(stencils.offsets);
  stencil_cells_ = std::move(stencils.cells);
  stencil_ends_ = std::move(stencils.ends);
  stencil_codes_ = std::move(stencils.codes);
}

// The particles counted into cells by chunks of consecutive indices, then each cell's first
// slot (cell_start_) and, per chunk, where its particles of each cell go (chunk_cell_fill_).
bool NeighborList::count_into_cells(std::size_t particle_count, std::size_t cell_count,
                                    int sort_chunks, const CountingChunkPass* first) {
  // Chunks of consecutive indices count their particles per cell; a cell's slots then hold
  // chunk 0's particles, then chunk 1's...: ascending index within a cell, the same slots
  // on any number of threads. The cells' first slots are then made in the same job, each
  // chunk's thread over its share of the cells from the particles below that share, which
  // the counting chunks count as well (made by the calling thread after the job, the other
  // chunks' counts crossing to its core: 4.1 ms of the 4000-sphere fluid's serial time on two
  // threads, 12 us a build, bench/README.md, "Stop 70").
  const auto sort_slots = static_cast<std::size_t>(sort_chunks);
  const std::int32_t* const cell_of = cell_of_.data();
  std::size_t* const cell_start = cell_start_.data();
  chunk_cell_fill_.resize(sort_slots);
  std::vector<std::int32_t> share_first(sort_slots, 0);  // each share's first cell
  for (std::size_t r = 1; r < sort_slots; ++r) {
    share_first[r] =
        static_cast<std::int32_t>(chunk_range(cell_count, static_cast<int>(r), sort_chunks).begin);
  }
  // [chunk][share]: the chunk's particles in the share's cells.
  std::vector<std::size_t> in_share(sort_slots * sort_slots, 0);
  std::vector<char> refused(sort_slots, 0);
  for_each_chunk_then(
      particle_count, cell_count, sort_chunks,
      [&](int c, std::size_t begin, std::size_t end) {
        std::vector<std::size_t>& count = chunk_cell_fill_[static_cast<std::size_t>(c)];
        count.assign(cell_count, 0);
        if (first && !(*first)(c, begin, end)) {
          refused[static_cast<std::size_t>(c)] = 1;
          return;
        }
        std::size_t* const in_cell = count.data();
        std::vector<std::size_t> shares(sort_slots, 0);
        if (sort_slots == 1) {
          for (std::size_t i = begin; i < end; ++i) ++in_cell[cell_of[i]];
          shares[0] = end - begin;
        } else {
          for (std::size_t i = begin; i < end; ++i) {
            const std::int32_t cell = cell_of[i];
            ++in_cell[cell];
            std::size_t share = 0;
            for (std::size_t r = 1; r < sort_slots; ++r) share += cell >= share_first[r] ? 1 : 0;
            ++shares[share];
          }
        }
        std::copy(shares.begin(), shares.end(),
                  in_share.begin() +
                      static_cast<std::ptrdiff_t>(static_cast<std::size_t>(c) * sort_slots));
      },
      [&](int share, std::size_t first_cell, std::size_t end_cell) {
        std::size_t filled = 0;
        for (std::size_t c = 0; c < sort_slots; ++c) {
          for (std::size_t r = 0; r < static_cast<std::size_t>(share); ++r) {
            filled += in_share[c * sort_slots + r];
          }
        }
        for (std::size_t cell = first_cell; cell < end_cell; ++cell) {
          cell_start[cell] = filled;
          for (std::vector<std::size_t>& fill : chunk_cell_fill_) {
            const std::size_t count = fill[cell];
            fill[cell] = filled;
            filled += count;
          }
        }
      });
  cell_start[cell_count] = particle_count;
  return std::find(refused.begin(), refused.end(), 1) == refused.end();
}

bool NeighborList::build(const std::vector<Vec3>& position, const Box& box,
                         const ChunkCheck* first) {
  const auto n = static_cast<std::int32_t>(position.size());
  const double reach = cutoff_ + skin_;
  const double reach2 = reach * reach;

  if (excluded_offsets_.size() != static_cast<std::size_t>(n) + 1) {
    excluded_offsets_.assign(static_cast<std::size_t>(n) + 1, 0);
    for (const auto& pair : excluded_) ++excluded_offsets_[pair[0] + 1];
    std::partial_sum(excluded_offsets_.begin(), excluded_offsets_.end(), excluded_offsets_.begin());
    // Every particle's excluded partners, either side of it, for the build's check.
    partner_offsets_.assign(static_cast<std::size_t>(n) + 1, 0);
    for (const auto& pair : excluded_)
      ++partner_offsets_[pair[0] + 1], ++partner_offsets_[pair[1] + 1];
    std::partial_sum(partner_offsets_.begin(), partner_offsets_.end(), partner_offsets_.begin());
    partners_.resize(partner_offsets_.back());
    std::vector<std::size_t> fill(partner_offsets_.begin(), partner_offsets_.end() - 1);
    for (const auto& pair : excluded_) {
      partners_[fill[pair[0]]++] = pair[1];
      partners_[fill[pair[1]]++] = pair[0];
    }
  }
  for (int code = 0; code < 27; ++code) {
    const int k[3] = {code % 3 - 1, (code / 3) % 3 - 1, code / 9 - 1};
    for (int a = 0; a < 3; ++a) image_shifts_[code][a] = k[a] * box.period()[a];
  }

  // Particles may sit up to half a skin outside the box between builds: bin and measure
  // their periodic images inside it, remembering by how many periods each was moved.
  std::vector<Vec3>& inside = inside_;
  std::vector<std::array<int, 3>>& moved = moved_;
  inside.resize(static_cast<std::size_t>(n));
  moved.resize(static_cast<std::size_t>(n));
  // Split as substantial items, as ForceEngine::ensure_neighbors' wrap. The same pass keeps
  // the positions for needs_rebuild and finds, per chunk, the largest coordinate (the float
  // scan's bounds) and whether any particle was moved: made after it on one thread, those
  // three passes over the particles left the other thread waiting at every build. False
  // where the caller's pass refuses the chunk.
  const int wrap_chunks = chunks_for(static_cast<std::size_t>(n));
  std::vector<double> chunk_largest(static_cast<std::size_t>(wrap_chunks), 0.0);
  std::vector<char> chunk_moved(static_cast<std::size_t>(wrap_chunks), 0);
  const bool keep_positions = &position != &position_at_build_;
  if (keep_positions) position_at_build_.resize(static_cast<std::size_t>(n));
  auto wrap_chunk = [&](int c, std::size_t begin, std::size_t end) {
    if (first && !(*first)(begin, end)) return false;
    double largest = 0.0;
    bool any_moved = false;
    for (std::size_t i = begin; i < end; ++i) {
      if (keep_positions) position_at_build_[i] = position[i];
      inside[i] = position[i];
      moved[i] = {0, 0, 0};
      box.wrap(inside[i], moved[i]);
      const Vec3& x = inside[i];
      largest = std::max({largest, std::abs(x.x), std::abs(x.y), std::abs(x.z)});
      any_moved |= (moved[i][0] | moved[i][1] | moved[i][2]) != 0;
    }
    chunk_largest[static_cast<std::size_t>(c)] = largest;
    chunk_moved[static_cast<std::size_t>(c)] = any_moved;
    return true;
  };

  // Counting sort of particles into cells; within a cell, ascending index.
  Grid grid;
  int cells = 0;
  std::vector<std::int32_t>& cell_of = cell_of_;
  std::vector<std::size_t>& cell_start = cell_start_;
  cell_of.resize(static_cast<std::size_t>(n));
  auto use_grid = [&] {
    const std::array<bool, 3> periodic{box.periodic(0), box.periodic(1), box.periodic(2)};
    if (!(grid == stencil_grid_) || periodic != stencil_periodic_ || stencil_offsets_.empty()) {
      make_stencils(grid, box);
    }
    cells = grid.count[0] * grid.count[1] * grid.count[2];
    cell_start.resize(static_cast<std::size_t>(cells) + 1);
  };
  auto bin = [&](std::size_t i) {
    int k[3];
    for (int a = 0; a < 3; ++a) {
      // Non-negative by construction (wrapped, or above the open-axis minimum): truncation
      // is the floor.
      k[a] = std::clamp(static_cast<int>((inside[i][a] - grid.origin[a]) * grid.inverse_width[a]),
                        0, grid.count[a] - 1);
    }
    cell_of[i] = (k[2] * grid.count[1] + k[1]) * grid.count[0] + k[0];
  };
  const int sort_chunks = wrap_chunks;
  bool usable = true;
  if (box.periodic(0) && box.periodic(1) && box.periodic(2)) {
    // The grid of a periodic box is the box's (make_grid reads no position): each chunk's
    // particles are wrapped, binned and counted into cells in one job, not three a build.
    grid = make_grid(inside, box);
    use_grid();
    const CountingChunkPass wrap_and_bin = [&](int c, std::size_t begin, std::size_t end) {
      if (!wrap_chunk(c, begin, end)) return false;
      for (std::size_t i = begin; i < end; ++i) bin(i);
      return true;
    };
    usable = count_into_cells(static_cast<std::size_t>(n), static_cast<std::size_t>(cells),
                              sort_chunks, &wrap_and_bin);
  } else {
    // Along an open axis the grid spans the particles' wrapped positions.
    std::vector<char> chunk_usable(static_cast<std::size_t>(wrap_chunks), 1);
    for_each_chunk(static_cast<std::size_t>(n), wrap_chunks,
                   [&](int c, std::size_t begin, std::size_t end) {
                     chunk_usable[static_cast<std::size_t>(c)] = wrap_chunk(c, begin, end);
                   });
    usable = std::find(chunk_usable.begin(), chunk_usable.end(), 0) == chunk_usable.end();
    if (usable) {
      grid = make_grid(inside, box);
      use_grid();
      parallel_for(static_cast<std::size_t>(n), bin);
      count_into_cells(static_cast<std::size_t>(n), static_cast<std::size_t>(cells), sort_chunks);
    }
  }
  if (!usable) {
    // Some chunks' build positions are this build's, the others' the last one's: no list.
    position_at_build_.clear();
    return false;
  }
  // Particles by slot (cell order), with their wrapped positions, periods moved and cells.
  std::vector<std::int32_t>& member = member_;
  std::vector<Vec3>& member_position = member_position_;
  std::vector<std::array<int, 3>>& member_moved = member_moved_;
  std::vector<std::int32_t>& member_cell = member_cell_;
  std::vector<std::size_t>& slot_of = slot_of_;
  member.resize(static_cast<std::size_t>(n));
  member_position.resize(static_cast<std::size_t>(n));
  member_x_.resize(static_cast<std::size_t>(n));
  member_y_.resize(static_cast<std::size_t>(n));
  member_z_.resize(static_cast<std::size_t>(n));
  // Single-precision copies only where the scan reads them (AVX2, image-coded grids).
  const bool float_copies = grid.shifted && scan_reads_floats();
  const std::size_t float_count = float_copies ? static_cast<std::size_t>(n) : 0;
  member_xf_.resize(float_count);
  member_yf_.resize(float_count);
  member_zf_.resize(float_count);
  member_moved.resize(static_cast<std::size_t>(n));
  member_cell.resize(static_cast<std::size_t>(n));
  member_moved_key_.resize(static_cast<std::size_t>(n));
  slot_of.resize(static_cast<std::size_t>(n));
  auto place = [&](std::int32_t i, std::size_t s) {
    slot_of[i] = s;
    member_position[s] = inside[i];
    member_x_[s] = inside[i].x;
    member_y_[s] = inside[i].y;
    member_z_[s] = inside[i].z;
    if (float_copies) {
      member_xf_[s] = static_cast<float>(inside[i].x);
      member_yf_[s] = static_cast<float>(inside[i].y);
      member_zf_[s] = static_cast<float>(inside[i].z);
    }
    member_moved[s] = moved[i];
    const std::array<int, 3>& k = moved[i];
    const bool small = std::abs(k[0]) <= 1 && std::abs(k[1]) <= 1 && std::abs(k[2]) <= 1;
    member_moved_key_[s] = small ? code_of(k[0], k[1], k[2]) : 27 + static_cast<std::int32_t>(s);
    member_cell[s] = cell_of[i];
    member[s] = i;
  };
  // Each counting chunk's particles to their slots (the scan's job, before its barrier).
  auto place_chunk = [&](int c, std::size_t begin, std::size_t end) {
    std::size_t* const fill = chunk_cell_fill_[static_cast<std::size_t>(c)].data();
    for (std::size_t i = begin; i < end; ++i)
      place(static_cast<std::int32_t>(i), fill[cell_of[i]]++);
  };

  // A pair found through stencil shift s (periods) between wrapped positions has, in the
  // caller's positions, the shift s + moved_i - moved_j; codes hold -1..1 periods per
  // axis, and anything else (positions far outside the box) drops the codes. Slots here.
  auto pair_code = [&](int stencil_code, std::size_t slot_i, std::size_t slot_j,
                       bool& coded) -> std::uint8_t {
    int k[3] = {stencil_code % 3 - 1, (stencil_code / 3) % 3 - 1, stencil_code / 9 - 1};
    for (int a = 0; a < 3; ++a) {
      k[a] += member_moved[slot_i][a] - member_moved[slot_j][a];
      if (k[a] < -1 || k[a] > 1) {
        coded = false;
        return kNoShift;
      }
    }
    return static_cast<std::uint8_t>(code_of(k[0], k[1], k[2]));
  };

  // The particles are visited slot by slot, in cell order, so that consecutive particles'
  // neighbouring cells are near each other in memory whatever the particles' index order;
  // a particle's partners come out in the same order either way (its cell's later slots,
  // then its stencil's cells), and the list by particle is rearranged from the list by slot.
  slot_offsets_.assign(static_cast<std::size_t>(n) + 1, 0);
  const bool any_exclusions = !excluded_.empty();
  // With cell order, the image-coded scan lists partners by slot at once (keep_hits), not as
  // particles renamed afterwards: a random read per pair fewer, and the member read only for
  // exclusions.
  const bool slots_listed = cell_order_ && grid.shifted;
  // The scan's first test in floats (FloatPositions): its bounds from the largest coordinate
  // of a candidate or an origin (a position less an image shift).
  FloatPositions in_float{member_xf_.data(), member_yf_.data(), member_zf_.data(), 0.0f, 0.0f};
  bool floats = false;
  if (float_copies) {
    const double largest = *std::max_element(chunk_largest.begin(), chunk_largest.end());
    double largest_shift = 0.0;
    for (const Vec3& shift : image_shifts_) {
      largest_shift =
          std::max({largest_shift, std::abs(shift.x), std::abs(shift.y), std::abs(shift.z)});
    }
    floats = float_bounds(largest + largest_shift, reach2, in_float.within2_below,
                          in_float.within2_above);
  }
  // Whether no particle was moved by a period into the box (the integrators keep positions
  // wrapped): then no pair needs its own image code, and keep_hits reads no moved keys.
  const bool moved_unshifted =
      std::find(chunk_moved.begin(), chunk_moved.end(), 1) == chunk_moved.end();
  // Chunks of consecutive slots, each listing its particles' partners in order; the lists
  // are then joined in chunk order: the same list on any number of threads.
  const int chunks = sort_chunks;
  chunk_neighbors_.resize(static_cast<std::size_t>(chunks));
  chunk_codes_.resize(static_cast<std::size_t>(chunks));
  chunk_hit_slots_.resize(static_cast<std::size_t>(chunks));
  chunk_hit_codes_.resize(static_cast<std::size_t>(chunks));
  std::vector<char> chunk_coded(static_cast<std::size_t>(chunks), 1);
  // Each chunk's lists are moved to its thread's stack for the scan and back after it.
  // Appended to in place, the vector objects (adjacent in chunk_neighbors_, several to a
  // cache line) would have each push_back of one thread take the line from the others: false
  // sharing, measured on 16 idle cores (LJ 32000, 300 steps): the scan 1.9 s on one thread,
  // 2.0-2.5 s on four, 1.1-1.3 s on eight; moved, 0.52 and 0.27 s.
  auto list_chunk = [&](int chunk, std::size_t begin, std::size_t end) {
    const auto k = static_cast<std::size_t>(chunk);
    std::vector<std::int32_t> out = std::move(chunk_neighbors_[k]);
    std::vector<std::uint8_t> out_codes = std::move(chunk_codes_[k]);
    // The entries in use; the vectors keep the last build's size, so that room for a
    // particle's hits is made without zeroing it again (resize() value-initialises what it
    // adds: 2 % of an LJ liquid's samples when made per particle), and are cut at the end.
    std::size_t used = 0;
    auto make_room = [&](std::size_t needed, bool codes) {
      if (out.size() < needed) out.resize(needed);
      if (codes && out_codes.size() < needed) out_codes.resize(needed);
    };
    bool coded = grid.shifted;
    // Copies of what the scan reads on every candidate: through this body's captured
    // references they would be reloaded after each store of a (uint8, may alias
    // anything) code, 8 % more instructions for the whole build (callgrind).
    const Vec3* const at = member_position.data();
    const double within2 = reach2;
    const bool shifted = grid.shifted;
    const bool as_slots = slots_listed;
    const Box here = box;
    // Candidates within reach, as member slots and shift codes. The scan appends
    // every candidate and advances only for hits: no branch on the distance test,
    // which the predictor would lose about a third of the time.
    std::vector<std::int32_t> hit_slot = std::move(chunk_hit_slots_[k]);
    std::vector<std::uint8_t> hit_code = std::move(chunk_hit_codes_[k]);
    hit_slot.resize(static_cast<std::size_t>(n) + 1 + kScanSlack);
    hit_code.resize(static_cast<std::size_t>(n) + 1 + kScanSlack);
    // keep_hits' hits to recode: their places in the list and hit numbers.
    thread_local std::vector<std::uint32_t> recode_kept, recode_hit;
    recode_kept.resize(static_cast<std::size_t>(n) + 1);
    recode_hit.resize(static_cast<std::size_t>(n) + 1);
    const double* const at_x = member_x_.data();
    const double* const at_y = member_y_.data();
    const double* const at_z = member_z_.data();
    const std::int32_t* const moved_key = member_moved_key_.data();
    double shifts[27][3];
    for (int code = 0; code < 27; ++code) {
      for (int a = 0; a < 3; ++a) shifts[code][a] = image_shifts_[code][a];
    }
    const StencilRuns runs{cell_start.data(), stencil_cells_.data(), stencil_ends_.data(),
                           stencil_codes_.data(), shifts};
    for (std::size_t slot = begin; slot < end; ++slot) {
      const std::int32_t i = member[slot];
      const Vec3 xi = at[slot];
      std::size_t hits = 0;
      auto scan = [&](std::size_t first, std::size_t last, int code) {
        const Vec3 origin = xi - image_shifts_[code];
        std::int32_t* slot_out = hit_slot.data();
        std::uint8_t* code_out = hit_code.data();
        for (std::size_t m = first; m < last; ++m) {
          const Vec3 d = here.minimum_image(at[m] - origin);
          slot_out[hits] = static_cast<std::int32_t>(m);
          code_out[hits] = static_cast<std::uint8_t>(code);
          hits += d.x * d.x + d.y * d.y + d.z * d.z < within2;
        }
      };
      const int c = member_cell[slot];
      std::size_t s = stencil_offsets_[c];
      if (shifted) {
        // The home cell's later slots, joined by the run that follows it in memory.
        std::size_t last = cell_start[c + 1];
        if (s < stencil_offsets_[c + 1] && stencil_cells_[s] == c + 1 &&
            stencil_codes_[s] == kNoShift) {
          last = cell_start[stencil_ends_[s++]];
        }
        hits = scan_stencil(at_x, at_y, at_z, runs, slot + 1, last, kNoShift, s,
                            stencil_offsets_[c + 1], xi.x, xi.y, xi.z, within2, hit_slot.data(),
                            hit_code.data(), floats ? &in_float : nullptr);
      } else {
        for (; s < stencil_offsets_[c + 1]; ++s) {
          scan(cell_start[stencil_cells_[s]], cell_start[stencil_ends_[s]], stencil_codes_[s]);
        }
      }
      // i's excluded partners (a chain bead's one or two bonded neighbours): a
      // linear scan.
      const std::int32_t* partners = partners_.data() + (any_exclusions ? partner_offsets_[i] : 0);
      const std::int32_t* partners_end =
          partners_.data() + (any_exclusions ? partner_offsets_[i + 1] : 0);
      // Room for every hit, written through pointers (no capacity test per partner), of
      // which those kept are used.
      const std::size_t listed = used;
      if (shifted) {
        // keep_hits stores whole vectors: room for kScanSlack more.
        make_room(listed + hits + kScanSlack, true);
        std::size_t recode = 0;
        const std::size_t kept = keep_hits(
            member.data(), moved_unshifted ? nullptr : moved_key, moved_key[slot], hit_slot.data(),
            hit_code.data(), hits, partners, static_cast<std::size_t>(partners_end - partners),
            out.data() + listed, out_codes.data() + listed, recode_kept.data(), recode_hit.data(),
            &recode, as_slots);
        // Both particles moved by the same periods into the box (nearly always: none), so
        // the stencil's shift stands; else the pair's own code.
        for (std::size_t r = 0; r < recode; ++r) {
          const std::size_t h = recode_hit[r];
          out_codes[listed + recode_kept[r]] =
              pair_code(hit_code[h], slot, static_cast<std::size_t>(hit_slot[h]), coded);
        }
        used = listed + kept;
        slot_offsets_[slot + 1] = used;
        continue;
      }
      // Without image codes (a box too narrow for them) each pair is met from both sides:
      // kept from its lower particle.
      make_room(listed + hits, false);
      std::int32_t* const kept_j = out.data() + listed;
      std::size_t kept = 0;
      for (std::size_t h = 0; h < hits; ++h) {
        const std::int32_t j = member[static_cast<std::size_t>(hit_slot[h])];
        if (j <= i) continue;
        if (std::find(partners, partners_end, j) != partners_end) continue;
        kept_j[kept++] = j;
      }
      used = listed + kept;
      // Counts within the chunk for now; made global offsets below.
      slot_offsets_[slot + 1] = used;
    }
    out.resize(used);
    out_codes.resize(shifted ? used : 0);
    chunk_coded[k] = coded;
    chunk_neighbors_[k] = std::move(out);
    chunk_codes_[k] = std::move(out_codes);
    chunk_hit_slots_[k] = std::move(hit_slot);
    chunk_hit_codes_[k] = std::move(hit_code);
  };
  // The particles placed, then (once every chunk has placed its own) the slots scanned: one
  // job, a barrier between (two jobs a build before). The scan's chunks of slots are the
  // counting chunks' number.
  for_each_chunk_then(static_cast<std::size_t>(n), static_cast<std::size_t>(n), sort_chunks,
                      place_chunk, list_chunk);
  std::vector<std::size_t> chunk_start(static_cast<std::size_t>(chunks) + 1, 0);
  for (int c = 0; c < chunks; ++c) {
    chunk_start[c + 1] = chunk_start[c] + chunk_neighbors_[static_cast<std::size_t>(c)].size();
  }
  bool coded = grid.shifted;
  for (char c : chunk_coded) coded = coded && c;
  const std::size_t pairs = chunk_start.back();
  // Without cell order the list by slot stays where it is; the list by particle is made from
  // it when first asked for (the force loop reads it in place through built_order()): each
  // particle's range in it, once every chunk's offsets are made.
  if (!cell_order_) {
    built_begin_.resize(static_cast<std::size_t>(n));
    built_end_.resize(static_cast<std::size_t>(n));
  }
  auto built_ranges = [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t s = slot_of[i];
      built_begin_[i] = slot_offsets_[s];
      built_end_[i] = slot_offsets_[s + 1];
    }
  };
  if (chunks == 1) {
    // One chunk is the joined list already: exchanged, not copied (each keeps its memory).
    slot_neighbors_.swap(chunk_neighbors_[0]);
    slot_codes_.swap(chunk_codes_[0]);
    if (!coded) slot_codes_.clear();
    if (!cell_order_) built_ranges(0, 0, static_cast<std::size_t>(n));
  } else {
    slot_neighbors_.resize(pairs);
    slot_codes_.resize(coded ? pairs : 0);
    auto join_chunk = [&](int chunk, std::size_t begin, std::size_t end) {
      const std::size_t base = chunk_start[static_cast<std::size_t>(chunk)];
      const std::vector<std::int32_t>& in = chunk_neighbors_[static_cast<std::size_t>(chunk)];
      std::copy(in.begin(), in.end(), slot_neighbors_.begin() + static_cast<std::ptrdiff_t>(base));
      if (coded) {
        const std::vector<std::uint8_t>& codes = chunk_codes_[static_cast<std::size_t>(chunk)];
        std::copy(codes.begin(), codes.end(),
                  slot_codes_.begin() + static_cast<std::ptrdiff_t>(base));
      }
      for (std::size_t slot = begin; slot < end; ++slot) slot_offsets_[slot + 1] += base;
    };
    if (cell_order_) {
      for_each_chunk(static_cast<std::size_t>(n), chunks, join_chunk);
    } else {
      // The particles' ranges after a barrier in the join's job (a job of their own before).
      for_each_chunk_then(static_cast<std::size_t>(n), static_cast<std::size_t>(n), chunks,
                          join_chunk, built_ranges);
    }
  }

  pairs_ = pairs;
  coded_ = coded;
  if (!cell_order_) {
    by_particle_.stale.store(true, std::memory_order_release);
  } else {
    // The list by slot, partners renamed by slot. The list by particle is made from it when
    // first asked for (the force loop reads this one; the thermo's curvature, contact rows
    // and Hessians that one): for an LJ liquid most builds are never asked.
    cell_ordered_.particle = member;
    cell_ordered_.offsets.swap(slot_offsets_);
    cell_ordered_.neighbors.swap(slot_neighbors_);
    cell_ordered_.image_codes.swap(slot_codes_);
    if (!slots_listed) {
      std::vector<std::int32_t>& list = cell_ordered_.neighbors;
      parallel_for(list.size(), [&](std::size_t k) {
        list[k] = static_cast<std::int32_t>(slot_of[static_cast<std::size_t>(list[k])]);
      });
    }
    built_begin_.clear();
    built_end_.clear();
    by_particle_.stale.store(true, std::memory_order_release);
  }
  ++builds_;
  return true;
}

// Each particle's partners moved from its slot (as particles, or with `slot_particle` as
// slots renamed to their particles).
void NeighborList::rearrange_by_particle(const std::size_t* slot_of,
                                         const std::size_t* slot_offsets,
                                         const std::int32_t* slot_neighbors,
                                         const std::int32_t* slot_particle,
                                         const std::uint8_t* slot_codes, std::size_t n) const {
  offsets_.resize(n + 1);
  offsets_[0] = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t s = slot_of[i];
    offsets_[i + 1] = offsets_[i] + (slot_offsets[s + 1] - slot_offsets[s]);
  }
  neighbors_.resize(pairs_);
  image_codes_.resize(coded_ ? pairs_ : 0);
  // A particle's partners (some 40 on a liquid) are a substantial item: split as the scan,
  // not in chunks of cheap_chunk_minimum() (the rigid melt's 4000 particles, then split from
  // 16384, moved on one thread).
  for_each_chunk(n, chunks_for(n), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t s = slot_of[i];
      const std::size_t from = slot_offsets[s], to = slot_offsets[s + 1];
      std::int32_t* const out = neighbors_.data() + offsets_[i];
      if (slot_particle) {
        for (std::size_t k = from; k < to; ++k) {
          out[k - from] = slot_particle[static_cast<std::size_t>(slot_neighbors[k])];
        }
      } else {
        std::copy(slot_neighbors + from, slot_neighbors + to, out);
      }
      if (coded_) std::copy(slot_codes + from, slot_codes + to, image_codes_.data() + offsets_[i]);
    }
  });
}

void NeighborList::make_by_particle() const {
  const std::lock_guard<std::mutex> lock(by_particle_.mutex);
  if (!by_particle_.stale.load(std::memory_order_acquire)) return;
  if (cell_order_) {
    rearrange_by_particle(slot_of_.data(), cell_ordered_.offsets.data(),
                          cell_ordered_.neighbors.data(), cell_ordered_.particle.data(),
                          cell_ordered_.image_codes.data(), cell_ordered_.particle.size());
  } else {
    rearrange_by_particle(slot_of_.data(), slot_offsets_.data(), slot_neighbors_.data(), nullptr,
                          slot_codes_.data(), built_begin_.size());
  }
  by_particle_.stale.store(false, std::memory_order_release);
}

NeighborList::PartnerRanges NeighborList::built_order() const {
  if (cell_order_ || built_begin_.empty()) return {};
  return {built_begin_.size(), slot_neighbors_.data(), coded_ ? slot_codes_.data() : nullptr,
          built_begin_.data(), built_end_.data()};
}

const std::vector<std::size_t>& NeighborList::pair_chunk_starts(int chunks) const {
  const std::size_t n = position_at_build_.size();
  const auto k = static_cast<std::size_t>(chunks);
  if (chunk_starts_build_ == builds_ && chunk_starts_.size() == k + 1) return chunk_starts_;
  chunk_starts_build_ = builds_;
  const std::vector<std::size_t>& offsets = cell_ordered_.offsets;
  if (cell_order_ && offsets.size() == n + 1 && offsets[n] > 0) {
    equal_work_starts(offsets.data(), n, chunks, chunk_starts_, true);
    return chunk_starts_;
  }
  chunk_starts_.assign(k + 1, n);
  for (std::size_t c = 0; c < k; ++c) {
    chunk_starts_[c] = fixed_chunk_range(n, static_cast<int>(c), chunks).begin;
  }
  return chunk_starts_;
}

const TouchedBlocks& NeighborList::touched_blocks(int chunks) const {
  const std::size_t n = position_at_build_.size();
  if (touched_build_ == builds_ && touched_.chunks() == chunks && touched_.items() == n) {
    return touched_;
  }
  touched_.clear(n, chunks);
  touched_build_ = builds_;
  if (n == 0) return touched_;
  const bool by_slot = cell_order_;
  const std::size_t* offsets = by_slot ? cell_ordered_.offsets.data() : slot_offsets_.data();
  const std::int32_t* neighbors = by_slot ? cell_ordered_.neighbors.data() : slot_neighbors_.data();
  const auto k = static_cast<std::size_t>(chunks);
  const std::size_t blocks = touched_.marks(0).size();
  // The slots in chunks of their own, each marking for every chunk of items; then the chunks'
  // marks joined.
  const std::vector<std::size_t>& first = pair_chunk_starts(chunks);
  const int scans = chunks_for(n);
  scan_marks_.resize(static_cast<std::size_t>(scans));
  const std::int32_t* member = member_.data();
  // The pointers by value: behind the lambda's references each char stored (which may alias
  // them) made the loop load them again, 5 cycles an entry.
  for_each_chunk(n, scans,
                 [&, by_slot, offsets, neighbors, member, k, blocks, first = first.data()](
                     int t, std::size_t begin, std::size_t end) {
                   std::vector<char>& mark = scan_marks_[static_cast<std::size_t>(t)];
                   mark.assign(k * blocks, 0);
                   char* const marks = mark.data();
                   for (std::size_t s = begin; s < end; ++s) {
                     const std::size_t owner = by_slot ? s : static_cast<std::size_t>(member[s]);
                     std::size_t c = 0;
                     while (c + 1 < k && owner >= first[c + 1]) ++c;
                     char* const m = marks + c * blocks;
                     m[TouchedBlocks::block_of(owner)] = 1;
                     const std::int32_t* const last = neighbors + offsets[s + 1];
                     for (const std::int32_t* j = neighbors + offsets[s]; j < last; ++j) {
                       m[TouchedBlocks::block_of(static_cast<std::size_t>(*j))] = 1;
                     }
                   }
                 });
  for (int c = 0; c < chunks; ++c) {
    std::vector<char>& joined = touched_.marks(c);
    for (const std::vector<char>& mark : scan_marks_) {
      const char* m = mark.data() + static_cast<std::size_t>(c) * blocks;
      for (std::size_t b = 0; b < blocks; ++b) joined[b] = static_cast<char>(joined[b] | m[b]);
    }
    touched_.make_runs(c);
  }
  return touched_;
}

NeighborList::PartnerRanges NeighborList::partner_ranges() const {
  const PartnerRanges built = built_order();
  if (built.begin) return built;
  by_particle();
  if (offsets_.empty()) return {};
  return {offsets_.size() - 1, neighbors_.data(), coded_ ? image_codes_.data() : nullptr,
          offsets_.data(), offsets_.data() + 1};
}

void NeighborList::set_cell_order(bool on) {
  // The list by particle of the last build, made before the list by slot goes.
  by_particle();
  cell_order_ = on;
  if (!on) cell_ordered_ = CellOrdered{};
  position_at_build_.clear();  // force a rebuild
}

bool NeighborList::needs_rebuild(const std::vector<Vec3>& position) const {
  if (position_at_build_.size() != position.size()) return true;
  // Written so that a NaN displacement asks for a rebuild too: the caller then finds the
  // non-finite position (a blown-up run) at no cost to the every-step check. Called twice a
  // step and nearly always passing: no allocation and no branch per particle (a count of
  // the particles beyond, per chunk, in a local array).
  const Vec3* now = position.data();
  constexpr int kMostChunks = 64;
  const int chunks = std::min(chunks_for_cheap(position.size()), kMostChunks);
  std::array<std::size_t, kMostChunks> beyond{};
  for_each_chunk(position.size(), chunks, [&](int c, std::size_t begin, std::size_t end) {
    std::size_t count = 0;
    for (std::size_t i = begin; i < end; ++i) count += !keeps_valid(i, now[i]);
    beyond[static_cast<std::size_t>(c)] = count;
  });
  for (int c = 0; c < chunks; ++c) {
    if (beyond[static_cast<std::size_t>(c)] > 0) return true;
  }
  return false;
}

}  // namespace deli
