#include "neighbor/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace deli {

NeighborList::NeighborList(double cutoff, double skin) : cutoff_(cutoff), skin_(skin) {}

void NeighborList::set_exclusions(std::vector<std::array<std::int32_t, 2>> excluded) {
  std::sort(excluded.begin(), excluded.end());
  excluded.erase(std::unique(excluded.begin(), excluded.end()), excluded.end());
  excluded_ = std::move(excluded);
  excluded_offsets_.clear();
  position_at_build_.clear();  // force a rebuild
}

bool NeighborList::is_excluded(std::int32_t i, std::int32_t j) const {
  const auto begin = excluded_.begin() + static_cast<std::ptrdiff_t>(excluded_offsets_[i]);
  const auto end = excluded_.begin() + static_cast<std::ptrdiff_t>(excluded_offsets_[i + 1]);
  return std::binary_search(begin, end, std::array<std::int32_t, 2>{i, j});
}

namespace {

// Cell grid over the box (periodic axes) or over the particles' extent (open axes), with
// cells at least `reach` wide so that all partners lie in the 27 surrounding cells.
struct CellGrid {
  std::array<int, 3> count{};
  Vec3 origin, inverse_width;
  std::array<bool, 3> periodic{};

  int axis_cell(double x, int a) const {
    int c = static_cast<int>(std::floor((x - origin[a]) * inverse_width[a]));
    if (periodic[a]) {
      c %= count[a];
      if (c < 0) c += count[a];
    }
    return std::clamp(c, 0, count[a] - 1);
  }
};

CellGrid make_grid(const std::vector<Vec3>& position, const Box& box, double reach) {
  CellGrid grid;
  for (int a = 0; a < 3; ++a) {
    grid.periodic[a] = box.periodic(a);
    double lo = box.lo()[a], extent = box.length()[a];
    if (!box.periodic(a)) {
      double lo_p = box.lo()[a], hi_p = box.hi()[a];
      for (const Vec3& x : position) lo_p = std::min(lo_p, x[a]), hi_p = std::max(hi_p, x[a]);
      lo = lo_p, extent = hi_p - lo_p;
    }
    grid.count[a] = std::max(1, static_cast<int>(std::min(extent / reach, 1024.0)));
    grid.origin[a] = lo;
    grid.inverse_width[a] = extent;  // extent for now; inverted below
  }
  // A sparse or spread-out system would get more cells than particles: coarser cells
  // (never narrower than `reach`) keep memory proportional to the particle count.
  const double limit = std::max(27.0, 2.0 * static_cast<double>(position.size()));
  while (static_cast<double>(grid.count[0]) * grid.count[1] * grid.count[2] > limit) {
    for (int& c : grid.count) c = (c + 1) / 2;
  }
  for (int a = 0; a < 3; ++a) {
    grid.inverse_width[a] = grid.count[a] / std::max(grid.inverse_width[a], 1e-300);
  }
  return grid;
}

}  // namespace

void NeighborList::build(const std::vector<Vec3>& position, const Box& box) {
  const auto n = static_cast<std::int32_t>(position.size());
  const double reach = cutoff_ + skin_;
  const double reach2 = reach * reach;

  excluded_offsets_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (const auto& pair : excluded_) ++excluded_offsets_[pair[0] + 1];
  std::partial_sum(excluded_offsets_.begin(), excluded_offsets_.end(), excluded_offsets_.begin());

  // Particles may sit up to half a skin outside the box between builds: bin and measure
  // their periodic images inside it.
  std::vector<Vec3> inside(position);
  for (Vec3& x : inside) {
    std::array<int, 3> image{};
    box.wrap(x, image);
  }

  // Cells half the reach wide (5^3 stencil) visit about half the volume of cells a full
  // reach wide (3^3 stencil); small periodic boxes fall back to the latter and, below
  // three cells along an axis, to minimum-image separations over distinct cells.
  int stencil_reach = 2;
  CellGrid grid = make_grid(inside, box, reach / 2);
  for (int a = 0; a < 3; ++a) {
    if (grid.periodic[a] && grid.count[a] < 5) stencil_reach = 1;
  }
  if (stencil_reach == 1) grid = make_grid(inside, box, reach);
  bool shifted = true;
  for (int a = 0; a < 3; ++a) {
    if (grid.periodic[a] && grid.count[a] < 3) shifted = false;
  }
  const int cells = grid.count[0] * grid.count[1] * grid.count[2];

  // Counting sort of particles into cells; within a cell, ascending index.
  std::vector<int> cell_of(static_cast<std::size_t>(n));
  std::vector<std::size_t> cell_start(static_cast<std::size_t>(cells) + 1, 0);
  for (std::int32_t i = 0; i < n; ++i) {
    const Vec3& x = inside[i];
    const int c = (grid.axis_cell(x.z, 2) * grid.count[1] + grid.axis_cell(x.y, 1)) * grid.count[0] +
                  grid.axis_cell(x.x, 0);
    cell_of[i] = c;
    ++cell_start[c + 1];
  }
  std::partial_sum(cell_start.begin(), cell_start.end(), cell_start.begin());
  std::vector<std::int32_t> cell_members(static_cast<std::size_t>(n));
  std::vector<Vec3> member_position(static_cast<std::size_t>(n));
  std::vector<std::size_t> slot_of(static_cast<std::size_t>(n));
  {
    std::vector<std::size_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::int32_t i = 0; i < n; ++i) {
      slot_of[i] = fill[cell_of[i]]++;
      member_position[slot_of[i]] = inside[i];
      cell_members[slot_of[i]] = i;
    }
  }

  // The cells around each cell: with enough cells along every periodic axis each is
  // reached through exactly one periodic shift (no minimum-image rounding); otherwise the
  // distinct cells within one cell, measured by minimum image.
  struct Neighbour {
    int cell;
    Vec3 shift;
  };
  const int span = shifted ? stencil_reach : 1;
  std::vector<Neighbour> around;
  auto cells_around = [&](int c) {
    around.clear();
    const std::array<int, 3> home{c % grid.count[0], (c / grid.count[0]) % grid.count[1],
                                  c / (grid.count[0] * grid.count[1])};
    for (int dz = -span; dz <= span; ++dz)
      for (int dy = -span; dy <= span; ++dy)
        for (int dx = -span; dx <= span; ++dx) {
          // Half stencil: of the offsets +o and -o only the lexicographically positive one,
          // so each pair of distinct cells is visited once (the home cell is handled apart).
          if (shifted && (dz < 0 || (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0))))) continue;
          std::array<int, 3> k{home[0] + dx, home[1] + dy, home[2] + dz};
          Vec3 shift;
          bool inside_grid = true;
          for (int a = 0; a < 3; ++a) {
            if (k[a] >= 0 && k[a] < grid.count[a]) continue;
            if (!grid.periodic[a]) {
              inside_grid = false;
              break;
            }
            const int wraps = k[a] < 0 ? -1 : 1;
            k[a] -= wraps * grid.count[a];
            shift[a] = wraps * box.period()[a];
          }
          if (!inside_grid) continue;
          around.push_back({(k[2] * grid.count[1] + k[1]) * grid.count[0] + k[0], shift});
        }
    if (!shifted) {
      std::sort(around.begin(), around.end(),
                [](const Neighbour& l, const Neighbour& r) { return l.cell < r.cell; });
      around.erase(std::unique(around.begin(), around.end(),
                               [](const Neighbour& l, const Neighbour& r) { return l.cell == r.cell; }),
                   around.end());
      for (Neighbour& e : around) e.shift = Vec3{};
    }
  };

  // Image codes: the shift of a pair in the caller's (possibly unwrapped) positions is the
  // stencil shift corrected by both particles' wrapping, a small multiple of the period
  // per axis; codes cover -1, 0, 1 periods, and anything else drops the codes.
  bool coded = shifted;
  for (int code = 0; code < 27; ++code) {
    const int c[3] = {code % 3 - 1, (code / 3) % 3 - 1, code / 9 - 1};
    for (int a = 0; a < 3; ++a) image_shifts_[code][a] = c[a] * box.period()[a];
  }
  auto code_of = [&](const Vec3& s) {
    int code = 0, weight = 1;
    for (int a = 0; a < 3; ++a, weight *= 3) {
      const double periods = box.period()[a] > 0 ? s[a] * box.inverse_period()[a] : 0.0;
      const long k = static_cast<long>(Box::round_to_integer(periods));
      if (k < -1 || k > 1) coded = false;
      code += static_cast<int>(k + 1) * weight;
    }
    return static_cast<std::uint8_t>(coded ? code : 13);
  };

  neighbors_.clear();
  image_codes_.clear();
  offsets_.assign(static_cast<std::size_t>(n) + 1, 0);
  std::vector<std::pair<std::int32_t, std::uint8_t>> found;
  for (std::int32_t i = 0; i < n; ++i) {
    found.clear();
    const Vec3 xi = inside[i];
    const Vec3 wrap_i = inside[i] - position[i];
    if (i == 0 || cell_of[i] != cell_of[i - 1]) cells_around(cell_of[i]);
    auto scan = [&](int cell, std::size_t first, const Vec3& shift) {
      const Vec3 origin = xi - shift;
      for (std::size_t m = first; m < cell_start[cell + 1]; ++m) {
        const std::int32_t j = cell_members[m];
        const Vec3 d = shifted ? member_position[m] - origin
                               : box.minimum_image(member_position[m] - origin);
        if (d.x * d.x + d.y * d.y + d.z * d.z >= reach2) continue;
        if (!shifted && j <= i) continue;
        // x_i - x_j - shift = -(d): shift = (x_i - x_j) + d in the caller's positions.
        const std::uint8_t code =
            shifted ? code_of(shift - wrap_i + (member_position[m] - position[j])) : 13;
        found.emplace_back(j, code);
      }
    };
    // Half stencil: partners later in the home cell, then the forward cells. The
    // minimum-image fallback scans every distinct cell and keeps j > i.
    if (shifted) scan(cell_of[i], slot_of[i] + 1, Vec3{});
    for (const Neighbour& e : around) scan(e.cell, cell_start[e.cell], e.shift);
    std::sort(found.begin(), found.end());
    for (const auto& [j, code] : found) {
      if (excluded_offsets_[std::min(i, j)] != excluded_offsets_[std::min(i, j) + 1] &&
          is_excluded(std::min(i, j), std::max(i, j))) {
        continue;
      }
      neighbors_.push_back(j);
      image_codes_.push_back(code);
    }
    offsets_[i + 1] = neighbors_.size();
  }
  if (!coded) image_codes_.clear();
  position_at_build_ = position;
  ++builds_;
}

bool NeighborList::needs_rebuild(const std::vector<Vec3>& position) const {
  if (position_at_build_.size() != position.size()) return true;
  const double limit2 = 0.25 * skin_ * skin_;
  for (std::size_t i = 0; i < position.size(); ++i) {
    if (norm2(position[i] - position_at_build_[i]) > limit2) return true;
  }
  return false;
}

bool NeighborList::update(const std::vector<Vec3>& position, const Box& box) {
  if (!needs_rebuild(position)) return false;
  build(position, box);
  return true;
}

}  // namespace deli
