#include "system/builders.hpp"

#include <cmath>
#include <random>
#include <string>
#include <unordered_map>

#include "core/error.hpp"

namespace deli {

System build_fcc(const FccLattice& lattice) {
  const double a = std::cbrt(4.0 / lattice.density);
  const auto [nx, ny, nz] = lattice.cells;
  System system;
  system.box = Box({0, 0, 0}, {nx * a, ny * a, nz * a}, {true, true, true});
  system.atom_types = {AtomType{lattice.mass, 0.5}};
  const Vec3 basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Particles& p = system.particles;
  p.resize(static_cast<std::size_t>(4 * nx * ny * nz));
  std::size_t n = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const Vec3& b : basis) {
          p.position[n] = Vec3{(i + b.x) * a, (j + b.y) * a, (k + b.z) * a};
          p.mass[n] = lattice.mass;
          p.id[n] = static_cast<std::int64_t>(n + 1);
          ++n;
        }
  return system;
}

namespace {

// Hash grid of placed beads for the min-distance test during chain growth.
class OccupancyGrid {
 public:
  OccupancyGrid(const Box& box, double min_distance) : box_(box), min2_(min_distance * min_distance) {
    for (int a = 0; a < 3; ++a) {
      count_[a] = std::max(1, static_cast<int>(box.length()[a] / min_distance));
    }
  }
  bool is_free(const std::vector<Vec3>& placed, const Vec3& x) const {
    const auto c = cell(x);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (std::size_t m : it->second) {
            if (norm2(box_.minimum_image(placed[m] - x)) < min2_) return false;
          }
        }
    return true;
  }
  void add(const Vec3& x, std::size_t index) { cells_[key(cell(x))].push_back(index); }
  void remove_last(const Vec3& x) { cells_[key(cell(x))].pop_back(); }

 private:
  std::array<int, 3> cell(const Vec3& x) const {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
      c[a] = static_cast<int>(std::floor((x[a] - box_.lo()[a]) / box_.length()[a] * count_[a]));
    }
    return c;
  }
  std::int64_t key(std::array<int, 3> c) const {
    for (int a = 0; a < 3; ++a) c[a] = ((c[a] % count_[a]) + count_[a]) % count_[a];
    return (static_cast<std::int64_t>(c[2]) * count_[1] + c[1]) * count_[0] + c[0];
  }
  const Box& box_;
  double min2_;
  std::array<int, 3> count_{};
  std::unordered_map<std::int64_t, std::vector<std::size_t>> cells_;
};

Vec3 random_unit_vector(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (;;) {
    const Vec3 v{normal(rng), normal(rng), normal(rng)};
    const double n = norm(v);
    if (n > 1e-12) return v * (1.0 / n);
  }
}

}  // namespace

System build_random_chains(const RandomChains& chains) {
  const std::size_t total = static_cast<std::size_t>(chains.count) * chains.length;
  const double side = std::cbrt(static_cast<double>(total) / chains.density);
  System system;
  system.box = Box({0, 0, 0}, {side, side, side}, {true, true, true});
  system.atom_types = {AtomType{chains.mass, 0.5}};
  system.topology.bond_types = chains.length > 1 ? 1 : 0;
  system.topology.angle_types = chains.angles && chains.length > 2 ? 1 : 0;

  Particles& p = system.particles;
  p.resize(total);
  std::mt19937_64 rng(chains.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  OccupancyGrid grid(system.box, chains.min_distance);
  std::array<int, 3> no_image{};

  std::size_t n = 0;
  for (int c = 0; c < chains.count; ++c) {
    for (int b = 0; b < chains.length; ++b) {
      bool placed = false;
      for (int attempt = 0; attempt < chains.attempts_per_bead && !placed; ++attempt) {
        Vec3 x;
        if (b == 0) {
          x = {side * uniform(rng), side * uniform(rng), side * uniform(rng)};
        } else {
          x = p.position[n - 1] + random_unit_vector(rng) * chains.bond_length;
        }
        system.box.wrap(x, no_image);
        no_image = {0, 0, 0};
        if (!grid.is_free(p.position, x)) continue;
        p.position[n] = x;
        placed = true;
      }
      if (!placed) {
        throw InputError("chain builder: could not place bead " + std::to_string(b + 1) +
                         " of chain " + std::to_string(c + 1) + " after " +
                         std::to_string(chains.attempts_per_bead) +
                         " attempts; lower the density or min_distance");
      }
      grid.add(p.position[n], n);
      p.mass[n] = chains.mass;
      p.id[n] = static_cast<std::int64_t>(n + 1);
      p.molecule[n] = c + 1;
      if (b > 0) {
        const auto i = static_cast<std::int32_t>(n);
        system.topology.bonds.push_back({i - 1, i, 0});
        if (chains.angles && b > 1) system.topology.angles.push_back({i - 2, i - 1, i, 0});
      }
      ++n;
    }
  }
  return system;
}

void assign_maxwell_boltzmann(Particles& particles, double temperature, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const std::size_t n = particles.size();
  Vec3 momentum;
  double mass = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double sd = std::sqrt(temperature / particles.mass[i]);
    particles.velocity[i] = {sd * normal(rng), sd * normal(rng), sd * normal(rng)};
    momentum += particles.velocity[i] * particles.mass[i];
    mass += particles.mass[i];
  }
  const Vec3 drift = momentum * (1.0 / mass);
  double twice_kinetic = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    particles.velocity[i] -= drift;
    twice_kinetic += particles.mass[i] * norm2(particles.velocity[i]);
  }
  const double dof = 3.0 * static_cast<double>(n) - 3.0;
  if (n < 2 || twice_kinetic <= 0.0) return;
  const double scale = std::sqrt(temperature * dof / twice_kinetic);
  for (Vec3& v : particles.velocity) v *= scale;
}

}  // namespace deli
