#include "system/particle_order.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <utility>

#include "constraints/union_find.hpp"

namespace deli {

ParticleOrder spatial_order(const System& system, double bin) {
  const Particles& particles = system.particles;
  const Box& box = system.box;
  const std::size_t n = particles.size();
  // Bins across the box, or across the particles along an axis without a period (they may
  // stand beyond a wall-free box's faces).
  Vec3 lo = box.lo(), hi = box.hi();
  for (int axis = 0; axis < 3; ++axis) {
    if (box.periodic(axis)) continue;
    for (const Vec3& x : particles.position) {
      lo[axis] = std::min(lo[axis], x[axis]);
      hi[axis] = std::max(hi[axis], x[axis]);
    }
  }
  std::array<std::int64_t, 3> bins{};
  for (int axis = 0; axis < 3; ++axis) {
    const double length = hi[axis] - lo[axis];
    const double count = bin > 0 && std::isfinite(length / bin) ? std::floor(length / bin) : 1.0;
    bins[axis] = static_cast<std::int64_t>(std::clamp(count, 1.0, 1024.0));
  }
  auto bin_of = [&](const Vec3& x) {
    std::int64_t key = 0;
    for (int axis = 2; axis >= 0; --axis) {
      const double length = hi[axis] - lo[axis];
      const double at = length > 0 ? (x[axis] - lo[axis]) / length * bins[axis] : 0.0;
      // A particle a rounding outside the box (or NaN) goes to the nearest end bin: only
      // the order depends on it.
      const auto b = static_cast<std::int64_t>(
          std::clamp(std::isnan(at) ? 0.0 : at, 0.0, static_cast<double>(bins[axis] - 1)));
      key = key * bins[axis] + b;
    }
    return key;
  };
  // The molecules (particles joined by bonds) as a union-find forest whose roots are their
  // smallest indices (of two roots joined, the larger points at the smaller); a molecule
  // takes its root's bin.
  std::vector<std::int32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (const Bond& b : system.topology.bonds) {
    const std::int32_t x = union_find_root(parent, b.i), y = union_find_root(parent, b.j);
    parent[static_cast<std::size_t>(std::max(x, y))] = std::min(x, y);
  }
  std::vector<std::pair<std::int64_t, std::int32_t>> key(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t head = union_find_root(parent, static_cast<std::int32_t>(i));
    key[i] = {bin_of(particles.position[static_cast<std::size_t>(head)]), head};
  }
  ParticleOrder order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::int32_t a, std::int32_t b) { return key[a] < key[b]; });
  return order;
}

bool is_identity(const ParticleOrder& order) {
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (order[k] != static_cast<std::int32_t>(k)) return false;
  }
  return true;
}

ParticleOrder inverse(const ParticleOrder& order) {
  ParticleOrder out(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    out[static_cast<std::size_t>(order[k])] = static_cast<std::int32_t>(k);
  }
  return out;
}

std::optional<ParticleOrder> order_of_ids(const std::vector<std::int64_t>& ids,
                                          const Particles& particles) {
  if (ids.size() != particles.size() || ids == particles.id) return std::nullopt;
  std::unordered_map<std::int64_t, std::int32_t> index_of;
  index_of.reserve(ids.size());
  for (std::size_t i = 0; i < particles.size(); ++i) {
    index_of.emplace(particles.id[i], static_cast<std::int32_t>(i));
  }
  ParticleOrder order;
  order.reserve(ids.size());
  std::vector<bool> taken(ids.size(), false);
  for (const std::int64_t id : ids) {
    const auto at = index_of.find(id);
    if (at == index_of.end() || taken[static_cast<std::size_t>(at->second)]) return std::nullopt;
    taken[static_cast<std::size_t>(at->second)] = true;
    order.push_back(at->second);
  }
  return order;
}

void reorder(System& system, const ParticleOrder& order) {
  Particles& p = system.particles;
  if (p.origin.empty()) {
    p.origin.resize(p.size());
    std::iota(p.origin.begin(), p.origin.end(), 0);
  }
  p.position = permuted(p.position, order);
  p.velocity = permuted(p.velocity, order);
  p.mass = permuted(p.mass, order);
  p.radius = permuted(p.radius, order);
  p.type = permuted(p.type, order);
  p.id = permuted(p.id, order);
  p.molecule = permuted(p.molecule, order);
  p.image = permuted(p.image, order);
  p.origin = permuted(p.origin, order);
  const ParticleOrder now = inverse(order);
  Topology& t = system.topology;
  for (Bond& b : t.bonds) b.i = now[b.i], b.j = now[b.j];
  for (Angle& a : t.angles) a.i = now[a.i], a.j = now[a.j], a.k = now[a.k];
  for (Dihedral& d : t.dihedrals) d.i = now[d.i], d.j = now[d.j], d.k = now[d.k], d.l = now[d.l];
}

System in_input_order(const System& system) {
  System out = system;
  if (system.particles.origin.empty()) return out;
  reorder(out, inverse(system.particles.origin));
  out.particles.origin.clear();
  return out;
}

}  // namespace deli
