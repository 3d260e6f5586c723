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
  system.atom_types.clear();
  for (double m : lattice.masses) system.atom_types.push_back(AtomType{m, 0.5});
  const auto types = lattice.masses.size();
  const Vec3 basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Particles& p = system.particles;
  p.resize(static_cast<std::size_t>(4 * nx * ny * nz));
  std::size_t n = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const Vec3& b : basis) {
          p.position[n] = Vec3{(i + b.x) * a, (j + b.y) * a, (k + b.z) * a};
          p.type[n] = static_cast<int>(n % types);
          p.mass[n] = lattice.masses[n % types];
          p.id[n] = static_cast<std::int64_t>(n + 1);
          ++n;
        }
  return system;
}

namespace {

// Hash grid of placed beads for the min-distance test during chain growth.
class OccupancyGrid {
 public:
  OccupancyGrid(const Box& box, double min_distance)
      : box_(box), min2_(min_distance * min_distance) {
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
  system.box = Box({0, 0, 0}, {side, side, side}, chains.periodic);
  system.atom_types = {AtomType{chains.mass, 0.5}};
  system.topology.bond_types = chains.length > 1 ? 1 : 0;
  auto inside_walls = [&](const Vec3& x) {
    for (int a = 0; a < 3; ++a) {
      if (chains.periodic[a]) continue;
      if (x[a] < chains.wall_clearance || x[a] > side - chains.wall_clearance) return false;
    }
    return true;
  };
  system.topology.angle_types = chains.angles && chains.length > 2 ? 1 : 0;
  system.topology.dihedral_types = chains.dihedrals && chains.length > 3 ? 1 : 0;

  Particles& p = system.particles;
  p.resize(total);
  std::mt19937_64 rng(chains.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  OccupancyGrid grid(system.box, chains.min_distance);

  // Grow bead by bead; a chain that walks into a dead end is removed and regrown from a new
  // random start, a bounded number of times.
  const int chain_attempts = 1000;
  std::size_t n = 0;
  for (int c = 0; c < chains.count; ++c) {
    const std::size_t first = n;
    bool grown = false;
    for (int chain_try = 0; chain_try < chain_attempts && !grown; ++chain_try) {
      n = first;
      grown = true;
      for (int b = 0; b < chains.length && grown; ++b) {
        bool placed = false;
        for (int attempt = 0; attempt < chains.attempts_per_bead && !placed; ++attempt) {
          Vec3 x = b == 0 ? Vec3{side * uniform(rng), side * uniform(rng), side * uniform(rng)}
                          : p.position[n - 1] + random_unit_vector(rng) * chains.bond_length;
          // Chains stay continuous when unwrapped: a bead's image flags continue its
          // predecessor's.
          std::array<int, 3> image = b == 0 ? std::array<int, 3>{} : p.image[n - 1];
          system.box.wrap(x, image);
          if (!inside_walls(x) || !grid.is_free(p.position, x)) continue;
          p.position[n] = x;
          p.image[n] = image;
          placed = true;
        }
        if (!placed) {
          for (std::size_t k = n; k-- > first;) grid.remove_last(p.position[k]);
          grown = false;
          break;
        }
        grid.add(p.position[n], n);
        ++n;
      }
    }
    if (!grown) {
      throw InputError("chain builder: could not grow chain " + std::to_string(c + 1) + " of " +
                       std::to_string(chains.count) + " in " + std::to_string(chain_attempts) +
                       " tries; lower the density or min_distance");
    }
    for (std::size_t k = first; k < n; ++k) {
      p.mass[k] = chains.mass;
      p.id[k] = static_cast<std::int64_t>(k + 1);
      p.molecule[k] = c + 1;
      const auto i = static_cast<std::int32_t>(k);
      if (k > first) system.topology.bonds.push_back({i - 1, i, 0});
      if (chains.angles && k > first + 1) system.topology.angles.push_back({i - 2, i - 1, i, 0});
      if (chains.dihedrals && k > first + 2) {
        system.topology.dihedrals.push_back({i - 3, i - 2, i - 1, i, 0});
      }
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
