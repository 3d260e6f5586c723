#include "input/run_input.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

#include "bonded/bond_styles.hpp"
#include "bonded/harmonic_angle.hpp"
#include "core/error.hpp"
#include "input/constraints_input.hpp"
#include "input/lammps_data.hpp"
#include "input/output_paths.hpp"
#include "input/thermostat_input.hpp"
#include "input/toml_table.hpp"
#include "integrators/thermostatted_integrator.hpp"
#include "integrators/velocity_verlet.hpp"
#include "pair/pair_coefficients.hpp"
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

double positive(TomlTable& t, const std::string& key, std::optional<double> fallback = {}) {
  const double v = t.number(key, fallback);
  if (!(v > 0.0) || !std::isfinite(v))
    t.fail("must be a positive number, found " + std::to_string(v), key);
  return v;
}

void set_box_periodicity(System& system, const std::array<bool, 3>& periodic) {
  system.box = Box(system.box.lo(), system.box.hi(), periodic);
}

// The force-field coefficients a data file carries (LAMMPS write_data writes them).
struct DataCoefficients {
  std::string file;
  CoefficientSection pair, pair_ij, bond, angle;
};

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
    coefficients = {file.path, std::move(file.pair), std::move(file.pair_ij), std::move(file.bond),
                    std::move(file.angle)};
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

int type_index(TomlTable& t, const std::string& key, double value, int count,
               const std::string& what) {
  if (value != std::floor(value) || value < 1 || value > count) {
    t.fail(what + " type " + std::to_string(value) + " does not exist: the system has " +
               std::to_string(count) + " " + what + " type(s), numbered from 1",
           key);
  }
  return static_cast<int>(value) - 1;
}

std::string where(const DataCoefficients& data, const CoefficientSection& section) {
  return data.file + ":" + std::to_string(section.line);
}

// The data file's section for a style the input names: its "# style" comment must agree.
void check_data_style(const DataCoefficients& data, const CoefficientSection& section,
                      const char* name, const std::vector<std::string>& styles,
                      const std::string& input_style) {
  if (section.line == 0 || section.style.empty()) return;
  if (std::find(styles.begin(), styles.end(), section.style) != styles.end()) return;
  throw InputError(where(data, section) + ": the data file's " + name + " are for style '" +
                   section.style + "', the input's is '" + input_style +
                   "': give every coefficient in the input's coeffs, or use a data file "
                   "written with write_data nocoeff");
}

std::string counted(std::size_t n, const std::string& what) {
  return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
}

std::optional<PairSpec> read_pair(TomlTable& t, const System& system, const DataCoefficients& data,
                                  std::vector<std::string>& notes) {
  const std::string style = t.choice("style", {"lj/cut", "wca", "none"});
  if (style == "none") {
    t.finish();
    return std::nullopt;
  }
  const int types = static_cast<int>(system.atom_types.size());
  const bool wca = style == "wca";
  const double global_cutoff = wca ? 0.0 : positive(t, "cutoff");
  const bool shift = wca ? true : t.boolean("shift", false);
  const Mixing mixing = t.choice("mixing", {"arithmetic", "geometric"}, "geometric") == "arithmetic"
                            ? Mixing::arithmetic
                            : Mixing::geometric;
  PairCoefficients coeffs(types, global_cutoff);
  // From the data file first (as read_data), then the input's coeffs, which win.
  std::size_t from_data = 0;
  const CoefficientSection* sections[] = {&data.pair, &data.pair_ij};
  for (const CoefficientSection* section : sections) {
    check_data_style(data, *section, section == &data.pair ? "Pair Coeffs" : "PairIJ Coeffs",
                     {"lj/cut"}, style);
    for (const CoefficientRow& row : section->rows) {
      const int a = row.types.front(), b = row.types.back();
      if (row.values.size() < 2 || row.values.size() > 3) {
        throw InputError(located(data.file, row.line,
                                 "lj/cut coefficients are epsilon sigma [cutoff], found " +
                                     std::to_string(row.values.size()) + " numbers"));
      }
      std::optional<double> cutoff;
      if (wca) {
        cutoff = std::pow(2.0, 1.0 / 6.0) * row.values[1];
      } else if (row.values.size() == 3) {
        cutoff = row.values[2];
      }
      coeffs.set(a, b, row.values[0], row.values[1], cutoff);
      ++from_data;
    }
  }
  std::set<std::pair<int, int>> given;
  for (TomlTable& c : t.tables("coeffs")) {
    const auto pair = c.numbers("types", 2);
    const int a = type_index(c, "types", pair[0], types, "atom");
    const int b = type_index(c, "types", pair[1], types, "atom");
    const double epsilon = c.number("epsilon");
    if (epsilon < 0) c.fail("must not be negative", "epsilon");
    const double sigma = positive(c, "sigma");
    std::optional<double> cutoff;
    if (wca) {
      cutoff = std::pow(2.0, 1.0 / 6.0) * sigma;
    } else if (c.has("cutoff")) {
      cutoff = positive(c, "cutoff");
    }
    if (!given.insert({std::min(a, b), std::max(a, b)}).second)
      c.fail("coefficients for this type pair were already given", "types");
    coeffs.set(a, b, epsilon, sigma, cutoff);
    c.finish();
  }
  if (from_data > 0) {
    notes.push_back("pair coefficients: " + counted(from_data, "entry") + " from " +
                    where(data, data.pair.line ? data.pair : data.pair_ij) +
                    (given.empty() ? ""
                                   : ", " + counted(given.size(), "entry") +
                                         " from the input (the input's win)"));
  }
  const std::vector<int> missing = coeffs.resolve(mixing);
  if (!missing.empty()) {
    t.fail("no coefficients for atom type " + std::to_string(missing.front() + 1) +
               " with itself; add {types = [" + std::to_string(missing.front() + 1) + ", " +
               std::to_string(missing.front() + 1) + "], epsilon = ..., sigma = ...} to coeffs",
           "coeffs");
  }
  t.finish();
  PairSpec spec;
  spec.style = wca ? PairSpec::Style::wca : PairSpec::Style::lj_cut;
  spec.shift = shift;
  spec.coefficients = std::move(coeffs);
  return spec;
}

// Coefficients per type: from the data file's section first (`from_data` turns a row's
// numbers into Params), then the input's coeffs, which win; every type must have some.
template <class Style>
std::vector<typename Style::Params> by_type(TomlTable& t, int types, const std::string& what,
                                            const auto& read_one, const DataCoefficients& data,
                                            const CoefficientSection& section,
                                            const auto& from_data,
                                            std::vector<std::string>& notes) {
  std::vector<typename Style::Params> params(static_cast<std::size_t>(types));
  std::vector<bool> given(static_cast<std::size_t>(types), false), in_data(given);
  for (const CoefficientRow& row : section.rows) {
    params[row.types.front()] = from_data(row);
    in_data[row.types.front()] = true;
  }
  std::size_t from_input = 0;
  for (TomlTable& c : t.tables("coeffs")) {
    const int k = type_index(c, "type", c.number("type"), types, what);
    if (given[k]) c.fail("coefficients for this " + what + " type were already given", "type");
    params[k] = read_one(c);
    given[k] = true;
    ++from_input;
    c.finish();
  }
  for (int k = 0; k < types; ++k) {
    if (!given[k] && !in_data[k]) {
      t.fail("no coefficients for " + what + " type " + std::to_string(k + 1) +
                 " (neither in the input nor in the data file); add {type = " +
                 std::to_string(k + 1) + ", ...} to coeffs",
             "coeffs");
    }
  }
  if (!section.rows.empty()) {
    notes.push_back(what + " coefficients: " + counted(section.rows.size(), "type") + " from " +
                    where(data, section) +
                    (from_input == 0 ? ""
                                     : ", " + counted(from_input, "type") +
                                           " from the input (the input's win)"));
  }
  return params;
}

// A data file's row for a style, checked for its number of coefficients.
void expect_values(const DataCoefficients& data, const CoefficientRow& row, std::size_t count,
                   const std::string& form) {
  if (row.values.size() != count) {
    throw InputError(
        located(data.file, row.line,
                "expected " + form + ", found " + std::to_string(row.values.size()) + " numbers"));
  }
}

std::optional<BondSpec> read_bond(std::optional<TomlTable> t, const System& system,
                                  bool rigid_bonds, const DataCoefficients& data,
                                  std::vector<std::string>& notes) {
  const int types = system.topology.bond_types;
  if (rigid_bonds) {
    if (t) t->fail("bonds are rigid rods ([constraints] bonds = \"rigid\"): remove this table");
    return std::nullopt;
  }
  if (!t) {
    if (!system.topology.bonds.empty()) {
      throw InputError(
          "the system has bonds but the input has no [forcefield.bond] table; "
          "add one with style = \"harmonic\" or \"fene\" and its coeffs");
    }
    return std::nullopt;
  }
  BondSpec spec;
  const std::string style = t->choice("style", {"harmonic", "fene"});
  check_data_style(data, data.bond, "Bond Coeffs", {style}, style);
  if (style == "harmonic") {
    spec.style = BondSpec::Style::harmonic;
    spec.harmonic = by_type<HarmonicBond>(
        *t, types, "bond",
        [](TomlTable& c) {
          return HarmonicBond::Params{c.number("k"), positive(c, "r0")};
        },
        data, data.bond,
        [&](const CoefficientRow& row) {
          expect_values(data, row, 2, "harmonic bond coefficients K r0");
          return HarmonicBond::Params{row.values[0], row.values[1]};
        },
        notes);
  } else {
    spec.style = BondSpec::Style::fene;
    spec.fene = by_type<FeneBond>(
        *t, types, "bond",
        [](TomlTable& c) {
          return FeneBond::Params{positive(c, "k"), positive(c, "r0"), c.number("epsilon"),
                                  positive(c, "sigma")};
        },
        data, data.bond,
        [&](const CoefficientRow& row) {
          expect_values(data, row, 4, "fene bond coefficients K R0 epsilon sigma");
          return FeneBond::Params{row.values[0], row.values[1], row.values[2], row.values[3]};
        },
        notes);
  }
  t->finish();
  return spec;
}

std::optional<AngleSpec> read_angle(std::optional<TomlTable> t, const System& system,
                                    const DataCoefficients& data, std::vector<std::string>& notes) {
  if (!t) {
    if (!system.topology.angles.empty()) {
      throw InputError(
          "the system has angles but the input has no [forcefield.angle] table; "
          "add one with style = \"harmonic\" and its coeffs");
    }
    return std::nullopt;
  }
  const std::string style = t->choice("style", {"harmonic"});
  check_data_style(data, data.angle, "Angle Coeffs", {style}, style);
  AngleSpec spec;
  spec.harmonic = by_type<HarmonicAngle>(
      *t, system.topology.angle_types, "angle",
      [](TomlTable& c) {
        return HarmonicAngle::Params{c.number("k"), c.number("theta0") * std::numbers::pi / 180.0};
      },
      data, data.angle,
      [&](const CoefficientRow& row) {
        expect_values(data, row, 2, "harmonic angle coefficients K theta0");
        return HarmonicAngle::Params{row.values[0], row.values[1] * std::numbers::pi / 180.0};
      },
      notes);
  t->finish();
  return spec;
}

ForceFieldSpec read_force_field(TomlTable& root, const System& system, bool rigid_bonds,
                                const DataCoefficients& data, std::vector<std::string>& notes) {
  ForceFieldSpec spec;
  auto t = root.table("forcefield");
  if (!t) root.fail("missing the [forcefield] table");
  if (auto special = t->table("special_bonds")) {
    const auto lj = special->numbers("lj", 3);
    for (int s = 0; s < 3; ++s) {
      if (lj[s] < 0 || lj[s] > 1) special->fail("factors must lie in [0, 1]", "lj");
      spec.special_lj[s] = lj[s];
    }
    special->finish();
  }
  auto pair = t->table("pair");
  if (!pair) t->fail("missing [forcefield.pair] (style = \"none\" for no pair interactions)");
  spec.pair = read_pair(*pair, system, data, notes);
  spec.bond = read_bond(t->table("bond"), system, rigid_bonds, data, notes);
  spec.angle = read_angle(t->table("angle"), system, data, notes);
  if (auto external = t->table("external")) {
    if (external->has("gravity")) {
      const auto g = external->numbers("gravity", 3);
      spec.gravity = Vec3{g[0], g[1], g[2]};
    }
    if (auto r = external->table("inverse_square")) {
      ForceFieldSpec::Radial radial;
      radial.inverse_square = true;
      radial.coefficients = {r->number("strength")};
      if (r->has("center")) {
        const auto c = r->numbers("center", 3);
        radial.center = {c[0], c[1], c[2]};
      }
      r->finish();
      spec.radial.push_back(radial);
    }
    if (auto r = external->table("radial_polynomial")) {
      ForceFieldSpec::Radial radial;
      const auto count = r->integer("degree") + 1;
      if (count < 1 || count > 16) r->fail("must be between 0 and 15", "degree");
      radial.coefficients = r->numbers("coefficients", static_cast<std::size_t>(count));
      if (r->has("center")) {
        const auto c = r->numbers("center", 3);
        radial.center = {c[0], c[1], c[2]};
      }
      r->finish();
      spec.radial.push_back(radial);
    }
    external->finish();
  }
  t->finish();
  return spec;
}

void check_box_fits_cutoff(const RunInput& input, const TomlTable& root) {
  const double cutoff = input.force_field->neighbor_cutoff();
  for (int a = 0; a < 3; ++a) {
    if (!input.system.box.periodic(a)) continue;
    const double length = input.system.box.length()[a];
    if (length < 2.0 * cutoff) {
      root.fail("the periodic box is " + std::to_string(length) + " long along " +
                std::string(1, "xyz"[a]) + ", less than twice the pair cutoff (" +
                std::to_string(cutoff) + "): make the box larger or the cutoff shorter");
    }
  }
}

// Numbers that are each finite can still combine into an infinite box (a tiny density, a
// huge lattice) or atoms the builders placed at infinity; nothing downstream checks that.
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

// Hard spheres must not overlap even where special_bonds takes a pair out of the force
// field's neighbour list (1-3, 1-4 neighbours): those pairs are checked on their own.
void add_excluded_contacts(RunInput& input) {
  if (!input.constraints.hard_spheres) return;
  const SpecialPairs special =
      find_special_pairs(input.system.topology, input.system.particles.size());
  for (int s = 1; s < 3; ++s) {
    if (input.force_field_spec.special_lj[s] == 1.0) continue;
    for (const auto& pair : special.by_separation[s]) {
      input.constraints.always_checked_pairs.push_back(pair);
    }
  }
}

}  // namespace

RunInput load_run_input(const std::string& path) {
  if (fs::is_directory(path)) {
    throw InputError(path + ": is a directory, not an input file; give the TOML input inside it");
  }
  std::ifstream file(path);
  if (!file) throw InputError(path + ": cannot read the input file (does it exist?)");
  std::stringstream text;
  text << file.rdbuf();
  return parse_run_input(text.str(), path);
}

RunInput parse_run_input(const std::string& text, const std::string& path) {
  toml::table doc;
  try {
    doc = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw InputError(
        located(path, static_cast<long>(e.source().begin.line), std::string(e.description())));
  }
  RunInput input;
  input.path = path;
  input.source_text = text;
  TomlTable root(doc, path, "");
  const fs::path dir = fs::path(path).parent_path();

  auto system = root.table("system");
  if (!system) root.fail("missing the [system] table");
  DataCoefficients data_coefficients;
  input.system = read_system(*system, dir, data_coefficients);
  input.data_file = data_coefficients.file;
  system->finish();
  input.start_temperature = read_velocities(root, input.system);
  check_system_is_finite(input.system, root);
  bool rigid_bonds = false;
  input.constraints = read_constraints(root.table("constraints"), input.system, rigid_bonds);
  input.force_field_spec =
      read_force_field(root, input.system, rigid_bonds, data_coefficients, input.notes);
  input.force_field = build_force_field(input.force_field_spec, input.system);

  if (auto n = root.table("neighbor")) {
    input.skin = n->number("skin", 0.3);
    if (input.skin < 0) n->fail("must not be negative", "skin");
    n->finish();
  }
  if (auto m = root.table("minimize")) {
    input.minimize.max_steps = m->integer("max_steps");
    if (input.minimize.max_steps < 0) m->fail("must not be negative", "max_steps");
    input.minimize.timestep = positive(*m, "timestep", 0.002);
    input.minimize.max_displacement = positive(*m, "max_displacement", 0.05);
    input.minimize.force_tolerance = positive(*m, "force_tolerance", 1e-3);
    m->finish();
  }
  auto integrator = root.table("integrator");
  if (!integrator) root.fail("missing the [integrator] table (type = \"verlet\", timestep = ...)");
  input.integrator = integrator->choice(
      "type", {"verlet", "gvi", "dsi", "midpoint", "direct", "collision"}, "verlet");
  const bool constrained = input.integrator == "gvi" || input.integrator == "dsi";
  if (input.integrator == "direct") {
    const std::string scheme =
        integrator->choice("scheme", {"midpoint", "newmark", "kane_imex"}, "midpoint");
    input.direct.scheme = scheme == "midpoint"  ? DirectScheme::midpoint
                          : scheme == "newmark" ? DirectScheme::newmark
                                                : DirectScheme::kane_imex;
    if (input.direct.scheme == DirectScheme::midpoint) {
      input.direct.alpha =
          integrator->choice("constraint_point", {"midpoint", "endpoint"}, "endpoint") == "midpoint"
              ? 0.5
              : 1.0;
    } else {
      input.direct.beta = integrator->number("beta", 0.25);
      input.direct.gamma = integrator->number("gamma", 0.5);
      if (!(input.direct.beta >= 0 && input.direct.beta <= 0.5)) {
        integrator->fail("Newmark's beta lies in [0, 1/2]", "beta");
      }
      if (!(input.direct.gamma >= 0 && input.direct.gamma <= 1)) {
        integrator->fail("Newmark's gamma lies in [0, 1]", "gamma");
      }
      if (input.direct.scheme == DirectScheme::newmark && input.direct.beta == 0) {
        integrator->fail(
            "direct Newmark with beta = 0 puts no constraint force at the step's end and "
            "cannot keep a constraint: use beta > 0 or scheme = \"kane_imex\"",
            "beta");
      }
    }
  } else if (input.integrator == "collision") {
    input.collision.base =
        integrator->choice("lagrangian", {"verlet", "midpoint"}, "verlet") == "midpoint"
            ? Lagrangian::midpoint
            : Lagrangian::verlet;
    input.collision.root_tolerance = positive(*integrator, "root_tolerance", 1e-12);
    input.collision.max_events_per_step =
        static_cast<int>(integrator->integer("max_events_per_step", 1000));
    if (input.collision.max_events_per_step < 1) {
      integrator->fail("must be at least 1", "max_events_per_step");
    }
    if (auto r = integrator->table("reflection")) {
      input.collision.energy =
          r->choice("energy", {"hamiltonian", "shadow"}, "hamiltonian") == "shadow"
              ? ReflectionEnergy::shadow
              : ReflectionEnergy::hamiltonian;
      if (input.collision.energy == ReflectionEnergy::shadow &&
          input.collision.base != Lagrangian::verlet) {
        r->fail(
            "the shadow Hamiltonian is Verlet's: use lagrangian = \"verlet\" or "
            "energy = \"hamiltonian\"",
            "energy");
      }
      r->finish();
    }
  } else if (constrained) {
    input.gvi.reflections = input.integrator == "gvi";
    input.gvi.lagrangian =
        integrator->choice("lagrangian", {"verlet", "midpoint"}, "verlet") == "midpoint"
            ? Lagrangian::midpoint
            : Lagrangian::verlet;
    input.gvi.constrained_predictor =
        integrator->choice("predictor", {"free", "constrained"}, "free") == "constrained";
    const std::string guard =
        integrator->choice("feasibility", {"restore", "reflect", "inelastic", "none"}, "restore");
    input.gvi.feasibility = guard == "restore"     ? Feasibility::restore
                            : guard == "reflect"   ? Feasibility::reflect
                            : guard == "inelastic" ? Feasibility::inelastic
                                                   : Feasibility::none;
    if (auto r = integrator->table("reflection")) {
      input.gvi.reflection =
          r->choice("operator", {"generalized", "moreau"}, "generalized") == "moreau"
              ? ReflectionOperator::moreau
              : ReflectionOperator::generalized;
      input.gvi.energy = r->choice("energy", {"hamiltonian", "shadow"}, "hamiltonian") == "shadow"
                             ? ReflectionEnergy::shadow
                             : ReflectionEnergy::hamiltonian;
      if (input.gvi.energy == ReflectionEnergy::shadow && input.force_field_spec.angle) {
        r->fail(
            "shadow-Hamiltonian reflections need the potential's pairwise Hessian, which "
            "harmonic angles lack: use energy = \"hamiltonian\"",
            "energy");
      }
      if (input.gvi.energy == ReflectionEnergy::shadow &&
          input.gvi.lagrangian != Lagrangian::verlet) {
        r->fail(
            "the shadow Hamiltonian is Verlet's: use lagrangian = \"verlet\" or "
            "energy = \"hamiltonian\"",
            "energy");
      }
      r->finish();
    }
  } else if (!input.constraints.empty()) {
    integrator->fail(
        "the input has [constraints]: they need type = \"gvi\" (or \"dsi\", or the "
        "baselines \"direct\" and \"collision\")",
        "type");
  } else if (input.integrator == "midpoint") {
    input.gvi.lagrangian = Lagrangian::midpoint;  // implicit midpoint, nothing to constrain
  }
  input.timestep = positive(*integrator, "timestep");
  integrator->finish();

  auto run = root.table("run");
  if (!run) root.fail("missing the [run] table (steps = ...)");
  input.steps = run->integer("steps");
  if (input.steps < 0) run->fail("must not be negative", "steps");
  run->finish();

  std::vector<OutputFile> output_files;
  if (auto output = root.table("output")) {
    if (auto thermo = output->table("thermo")) {
      input.thermo.every = thermo->integer("every", 100);
      if (input.thermo.every < 0) thermo->fail("must not be negative", "every");
      input.thermo.file = thermo->string("file", "");
      output_files.push_back({"thermo", input.thermo.file, *thermo});
      thermo->finish();
    }
    if (auto checkpoint = output->table("checkpoint")) {
      input.checkpoint.file = checkpoint->string("file");
      output_files.push_back({"checkpoint", input.checkpoint.file, *checkpoint});
      input.checkpoint.every = checkpoint->integer("every", 10000);
      if (input.checkpoint.every < 1) checkpoint->fail("must be at least 1", "every");
      checkpoint->finish();
    }
    if (auto dump = output->table("dump")) {
      input.dump.file = dump->string("file");
      output_files.push_back({"dump", input.dump.file, *dump});
      input.dump.format = dump->choice("format", {"lammps", "xyz"}, "lammps");
      // Extended XYZ names type k by the element of atomic number k (ASE reads no others).
      if (input.dump.format == "xyz" && input.system.atom_types.size() > 118) {
        dump->fail("names atom types by element symbols, 118 at most; this system has " +
                       std::to_string(input.system.atom_types.size()) +
                       " types: use format = \"lammps\"",
                   "format");
      }
      input.dump.every = dump->integer("every", 1000);
      if (input.dump.every < 1) dump->fail("must be at least 1", "every");
      dump->finish();
    }
    if (auto trajectory = output->table("trajectory")) {
      input.trajectory.file = trajectory->string("file");
      output_files.push_back({"trajectory", input.trajectory.file, *trajectory});
      input.trajectory.every = trajectory->integer("every", 1000);
      if (input.trajectory.every < 1) trajectory->fail("must be at least 1", "every");
      input.trajectory.velocities = trajectory->boolean("velocities", true);
      input.trajectory.images = trajectory->boolean("images", true);
      input.trajectory.forces = trajectory->boolean("forces", false);
      input.trajectory.compression = static_cast<int>(trajectory->integer("compression", 4));
      if (input.trajectory.compression < 0 || input.trajectory.compression > 9) {
        trajectory->fail("deflate level from 0 (none) to 9", "compression");
      }
      trajectory->finish();
    }
    input.final_data = output->string("final_data", "");
    output_files.push_back({"final data", input.final_data, *output, "final_data"});
    input.log = output->string("log", "");
    output_files.push_back({"log", input.log, *output, "log"});
    output->finish();
  }
  input.thermostat = read_thermostat(root.table("thermostat"));
  root.finish();
  std::vector<std::pair<std::string, std::string>> inputs{{"input file", path}};
  if (!input.data_file.empty()) inputs.emplace_back("data file", input.data_file);
  check_output_paths(output_files, inputs);
  check_box_fits_cutoff(input, root);
  input.degrees_of_freedom = run_degrees_of_freedom(input.system, input.constraints,
                                                    input.force_field_spec, input.thermostat);
  // Key order and formatting are toml++'s own, so comments and layout do not count.
  std::ostringstream model;
  for (const char* table : {"forcefield", "constraints"}) {
    if (const toml::table* t = doc[table].as_table()) model << "[" << table << "]\n" << *t << "\n";
  }
  input.model_text = model.str();
  input.gvi.timestep = input.timestep;
  input.gvi.skin = input.skin;
  add_excluded_contacts(input);
  return input;
}

namespace {
std::unique_ptr<Integrator> make_constant_energy_integrator(const RunInput& input) {
  const Particles& particles = input.system.particles;
  if (input.integrator == "verlet") {
    return std::make_unique<VelocityVerlet>(*input.force_field, input.skin, input.timestep);
  }
  if (input.integrator == "direct") {
    return std::make_unique<DirectSubstitution>(
        *input.force_field, input.constraints, input.timestep, input.skin, input.direct, particles);
  }
  if (input.integrator == "collision") {
    return std::make_unique<CollisionIntegrator>(*input.force_field, input.constraints,
                                                 input.timestep, input.skin, input.collision,
                                                 particles);
  }
  // gvi, dsi, midpoint: one integrator, options
  return std::make_unique<Gvi>(*input.force_field, input.constraints, input.gvi, particles);
}
}  // namespace

std::unique_ptr<Integrator> make_integrator(const RunInput& input) {
  std::unique_ptr<Integrator> integrator = make_constant_energy_integrator(input);
  if (!input.thermostat) return integrator;
  return std::make_unique<ThermostattedIntegrator>(std::move(integrator), *input.thermostat,
                                                   input.degrees_of_freedom);
}

}  // namespace deli
