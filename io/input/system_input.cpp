#include "input/system_input.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "input/lammps_data.hpp"
#include "system/builders.hpp"

namespace deli {

namespace {

namespace fs = std::filesystem;

std::array<bool, 3> read_boundary(TomlTable& t) {
  std::array<bool, 3> periodic{true, true, true};
  if (!t.has("boundary")) return periodic;
  const std::string b = t.string("boundary");
  if (b.size() != 3)
    t.fail("expected three letters, p (periodic) or f (open), e.g. \"ppf\"", "boundary");
  for (int a = 0; a < 3; ++a) {
    if (b[a] != 'p' && b[a] != 'f') {
      t.fail(std::string("letter '") + b[a] + "' is neither p (periodic) nor f (open)", "boundary");
    }
    periodic[a] = b[a] == 'p';
  }
  return periodic;
}

void set_box_periodicity(System& system, const std::array<bool, 3>& periodic) {
  system.box = Box(system.box.lo(), system.box.hi(), periodic);
}

}  // namespace

System read_system(TomlTable& t, const fs::path& input_dir, DataCoefficients& coefficients) {
  const std::array<bool, 3> periodic = read_boundary(t);
  const bool from_data = t.has("data");
  auto lattice = t.table("lattice");
  auto chains = t.table("chains");
  const int sources = int(from_data) + int(lattice.has_value()) + int(chains.has_value());
  if (sources != 1) {
    t.fail("give exactly one of 'data' (a LAMMPS data file), [system.lattice] or [system.chains]");
  }
  System system;
  if (from_data) {
    fs::path data = t.string("data");
    if (data.is_relative()) data = input_dir / data;
    LammpsDataOptions options;
    options.periodic = periodic;
    options.atom_style =
        t.choice("atom_style", {"", "atomic", "bond", "angle", "molecular", "full"}, "");
    if (!fs::exists(data)) t.fail("file " + data.string() + " does not exist", "data");
    LammpsDataFile file = read_lammps_data(data.string(), options);
    coefficients = {file.path,
                    std::move(file.pair),
                    std::move(file.pair_ij),
                    std::move(file.bond),
                    std::move(file.angle),
                    std::move(file.dihedral)};
    system = std::move(file.system);
  } else if (lattice) {
    FccLattice f;
    lattice->choice("type", {"fcc"});
    f.density = positive(*lattice, "density");
    const auto cells = lattice->numbers("cells", 3);
    for (int a = 0; a < 3; ++a) {
      if (cells[a] < 1 || cells[a] != std::floor(cells[a]))
        lattice->fail("cells must be positive integers", "cells");
      if (cells[a] > 1e6) lattice->fail("at most 1000000 cells per axis", "cells");
      f.cells[a] = static_cast<int>(cells[a]);
    }
    if (lattice->has("masses")) {
      const auto count = lattice->integer("types", 1);
      if (count < 1) lattice->fail("must be at least 1", "types");
      f.masses = lattice->numbers("masses", static_cast<std::size_t>(count));
      for (double m : f.masses) {
        if (!(m > 0)) lattice->fail("masses must be positive", "masses");
      }
    } else {
      const auto count = lattice->integer("types", 1);
      if (count < 1) lattice->fail("must be at least 1", "types");
      f.masses.assign(static_cast<std::size_t>(count), positive(*lattice, "mass", 1.0));
    }
    lattice->finish();
    if (4.0 * f.cells[0] * f.cells[1] * f.cells[2] > std::numeric_limits<std::int32_t>::max()) {
      lattice->fail("4 x " + std::to_string(f.cells[0]) + " x " + std::to_string(f.cells[1]) +
                        " x " + std::to_string(f.cells[2]) +
                        " atoms: more than deli's limit of 2147483647 atoms",
                    "cells");
    }
    system = build_fcc(f);
    set_box_periodicity(system, periodic);
  } else {
    RandomChains c;
    const std::int64_t count = chains->integer("count"), length = chains->integer("length");
    if (count < 1 || length < 1) chains->fail("count and length must be at least 1");
    if (static_cast<double>(count) * static_cast<double>(length) >
        std::numeric_limits<std::int32_t>::max()) {
      chains->fail(std::to_string(count) + " chains of " + std::to_string(length) +
                   " atoms: more than deli's limit of 2147483647 atoms");
    }
    c.count = static_cast<int>(count);
    c.length = static_cast<int>(length);
    c.density = positive(*chains, "density");
    c.bond_length = positive(*chains, "bond_length", 0.97);
    c.min_distance = positive(*chains, "min_distance", 0.9);
    // Each bead is placed bond_length from the one before it and at least min_distance from
    // every bead placed, that one included: otherwise no chain can grow, and the builder
    // would spend its every try (seconds) before saying so.
    if (c.length > 1 && !(c.min_distance < c.bond_length)) {
      chains->fail("must be less than bond_length (" + std::to_string(c.bond_length) +
                       "): each bead sits bond_length from the one before it",
                   "min_distance");
    }
    c.mass = positive(*chains, "mass", 1.0);
    c.angles = chains->boolean("angles", false);
    c.dihedrals = chains->boolean("dihedrals", false);
    c.seed = static_cast<std::uint64_t>(chains->integer("seed", 1));
    c.periodic = periodic;
    c.wall_clearance = chains->number("wall_clearance", 0.0);
    if (c.wall_clearance < 0) chains->fail("must not be negative", "wall_clearance");
    chains->finish();
    system = build_random_chains(c);
    set_box_periodicity(system, periodic);
  }
  return system;
}

std::optional<double> read_velocities(TomlTable& root, System& system) {
  auto v = root.table("velocities");
  if (!v) return std::nullopt;
  const double temperature = v->number("temperature");
  if (temperature < 0) v->fail("must not be negative", "temperature");
  const auto seed = v->integer("seed");
  v->finish();
  assign_maxwell_boltzmann(system.particles, temperature, static_cast<std::uint64_t>(seed));
  return temperature;
}

void check_system_is_finite(const System& system, const TomlTable& root) {
  const Vec3 length = system.box.length();
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(length[a]) || !(length[a] > 0)) {
      root.fail("the box length along " + std::string(1, "xyz"[a]) + " is " +
                std::to_string(length[a]) +
                ": not a finite positive length; check the box "
                "bounds, the density and the number of cells");
    }
  }
  if (!std::isfinite(system.box.volume())) {
    root.fail("the box volume overflows (box " + std::to_string(length.x) + " x " +
              std::to_string(length.y) + " x " + std::to_string(length.z) +
              "); check the box bounds, the density and the number of cells");
  }
  const Particles& p = system.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(p.position[i][k]) || !std::isfinite(p.velocity[i][k])) {
        root.fail("atom " + std::to_string(p.id[i]) +
                  " has a position or velocity that is not finite; check the system's numbers");
      }
    }
  }
}

}  // namespace deli
