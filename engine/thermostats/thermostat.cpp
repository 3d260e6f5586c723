#include "thermostats/thermostat.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"
#include "thermostats/normal_triples.hpp"
#include "thermostats/random_stream.hpp"

namespace deli {

namespace {
enum Stream : std::uint32_t { langevin = 1, csvr = 2 };

// The counter of a draw: atom id (all ones for a global draw), step, which thermostat and
// which half of the step; the low 16 bits count the draws (steps up to 2^39).
PhiloxCounter draw_counter(std::uint64_t id, std::int64_t step, Stream stream, int half) {
  const auto s = static_cast<std::uint64_t>(step);
  return {static_cast<std::uint32_t>(id), static_cast<std::uint32_t>(id >> 32),
          static_cast<std::uint32_t>(s),
          (static_cast<std::uint32_t>(stream) << 30) | (static_cast<std::uint32_t>(half) << 29) |
              (static_cast<std::uint32_t>((s >> 32) & 0x7f) << 16)};
}
}  // namespace

void LangevinThermostat::apply(Particles& p, std::int64_t step, int half, double duration) {
  const double c = std::exp(-duration / settings_.damping);
  const double noise = std::sqrt((1.0 - c * c) * settings_.temperature);
  // Each atom's draws depend on its id and the step alone: any number of threads, any
  // chunks. Drawn a block of atoms at a time (normal_triples: eight streams at once where
  // the build has AVX-512; drawn one by one, they were most of the thermostat's time).
  const std::size_t n = p.size();
  for_each_chunk(n, chunks_for(n), [&, c, noise](int, std::size_t begin, std::size_t end) {
    constexpr std::size_t block = 64;
    PhiloxCounter start[block];
    Vec3 normal[block];
    for (std::size_t first = begin; first < end; first += block) {
      const std::size_t count = std::min(block, end - first);
      for (std::size_t k = 0; k < count; ++k) {
        start[k] =
            draw_counter(static_cast<std::uint64_t>(p.id[first + k]), step, Stream::langevin, half);
      }
      normal_triples(settings_.seed, start, count, normal);
      // The atoms' noise amplitudes noise / sqrt(m) as packets (std::sqrt, which may set
      // errno, does not vectorise; a root and a division per atom were 3 % of an LJ
      // liquid's Langevin loop): the same numbers.
      double amplitude[block];
      const auto length = static_cast<Eigen::Index>(count);
      Eigen::Map<Eigen::ArrayXd>(amplitude, length) =
          noise / Eigen::Map<const Eigen::ArrayXd>(p.mass.data() + first, length).sqrt();
      for (std::size_t k = 0; k < count; ++k) {
        const std::size_t i = first + k;
        const double sd = amplitude[k];
        Vec3& v = p.velocity[i];
        const Vec3& r = normal[k];
        v = {c * v.x + sd * r.x, c * v.y + sd * r.y, c * v.z + sd * r.z};
      }
    }
  });
}

void CsvrThermostat::apply(Particles& p, std::int64_t step, int half, double duration) {
  const double twice_kinetic = ordered_sum<double>(
      p.size(), [&](std::size_t i) { return p.mass[i] * norm2(p.velocity[i]); });
  const double kinetic = 0.5 * twice_kinetic;
  if (!(kinetic > 0.0) || dof_ <= 0) return;
  RandomStream random(settings_.seed, draw_counter(~std::uint64_t{0}, step, Stream::csvr, half));
  const double c = std::exp(-duration / settings_.damping);
  const double target = 0.5 * dof_ * settings_.temperature;
  const double r1 = random.normal();
  // The sum of dof - 1 squared standard normals is 2 Gamma((dof - 1) / 2).
  const double others = dof_ > 1.0 ? 2.0 * random.gamma(0.5 * (dof_ - 1.0)) : 0.0;
  const double next = kinetic + (1.0 - c) * (target * (r1 * r1 + others) / dof_ - kinetic) +
                      2.0 * r1 * std::sqrt(c * (1.0 - c) * kinetic * target / dof_);
  const double scale = std::sqrt(std::max(next, 0.0) / kinetic);
  parallel_for(p.size(), [&](std::size_t i) { p.velocity[i] *= scale; });
}

std::unique_ptr<Thermostat> make_thermostat(const ThermostatSettings& settings,
                                            const DegreesOfFreedom& dof) {
  if (settings.kind == ThermostatKind::langevin)
    return std::make_unique<LangevinThermostat>(settings);
  return std::make_unique<CsvrThermostat>(settings, dof.count());
}

}  // namespace deli
