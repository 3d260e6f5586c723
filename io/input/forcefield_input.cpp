#include "input/forcefield_input.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <sstream>

#include "bonded/bonded_style.hpp"
#include "core/error.hpp"
#include "pair/pair_style.hpp"

namespace deli {

namespace {

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

// The data file's section for a style the input names: its "# style" comment must agree,
// unless it is a hybrid section, whose rows must each name their style (checked against
// the styles by the caller).
void check_data_style(const DataCoefficients& data, const CoefficientSection& section,
                      const char* name, const std::vector<std::string>& styles,
                      const std::string& input_style) {
  if (section.line == 0 || section.style.empty()) return;
  if (section.style == "hybrid") {
    for (const CoefficientRow& row : section.rows) {
      if (!row.style.empty()) continue;
      throw InputError(located(data.file, row.line,
                               std::string("the data file's ") + name +
                                   " are marked '# hybrid' but this row names no style: write "
                                   "it as 'type style coefficients...' (\"1 fene 30 1.5 1 1\")"));
    }
    return;
  }
  if (std::find(styles.begin(), styles.end(), section.style) != styles.end()) return;
  throw InputError(where(data, section) + ": the data file's " + name + " are for style '" +
                   section.style + "', the input's is '" + input_style +
                   "': give every coefficient in the input's coeffs, or use a data file "
                   "written with write_data nocoeff");
}

std::string counted(std::size_t n, const std::string& what) {
  return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
}

std::string number_text(double v) {
  std::ostringstream text;
  text << v;
  return text.str();
}

// One coefficient from the input, checked as its style's registration says.
double read_coefficient(TomlTable& c, const StyleCoefficient& k) {
  switch (k.check) {
    case StyleCoefficient::Check::positive:
      return positive(c, k.name);
    case StyleCoefficient::Check::non_negative: {
      const double v = c.number(k.name);
      if (v < 0) c.fail("must not be negative", k.name);
      return v;
    }
    case StyleCoefficient::Check::sign:
    case StyleCoefficient::Check::non_negative_integer: {
      const double v = c.number(k.name);
      const std::string violation = coefficient_violation(k.check, v);
      if (!violation.empty()) c.fail(violation + ", found " + number_text(v), k.name);
      return v;
    }
    case StyleCoefficient::Check::any:
      break;
  }
  return c.number(k.name);
}

std::optional<PairSpec> read_pair(TomlTable& t, const System& system, const DataCoefficients& data,
                                  std::vector<std::string>& notes) {
  std::vector<std::string> names;
  for (const PairStyle* style : pair_styles()) names.push_back(style->name);
  names.push_back("none");
  const std::string name = t.choice("style", names);
  if (name == "none") {
    t.finish();
    return std::nullopt;
  }
  const PairStyle& style = *find_pair_style(name);
  const std::size_t count = style.coefficients.size();
  const int types = static_cast<int>(system.atom_types.size());
  const double global_cutoff = style.fixed_cutoff ? 0.0 : positive(t, "cutoff");
  const bool shift = style.always_shifted ? true : t.boolean("shift", false);
  const Mixing mixing = t.choice("mixing", {"arithmetic", "geometric"}, "geometric") == "arithmetic"
                            ? Mixing::arithmetic
                            : Mixing::geometric;
  PairCoefficients coeffs(types, global_cutoff);
  // From the data file first (as read_data), then the input's coeffs, which win.
  std::size_t from_data = 0;
  const CoefficientSection* sections[] = {&data.pair, &data.pair_ij};
  for (const CoefficientSection* section : sections) {
    check_data_style(data, *section, section == &data.pair ? "Pair Coeffs" : "PairIJ Coeffs",
                     {style.lammps_style}, name);
    for (const CoefficientRow& row : section->rows) {
      if (!row.style.empty() && row.style != style.lammps_style) {
        throw InputError(located(data.file, row.line,
                                 "this row is for pair style '" + row.style +
                                     "', the input's is '" + name +
                                     "': deli has one pair style per system (no pair_style "
                                     "hybrid); give the coefficients in the input's coeffs"));
      }
      const int a = row.types.front(), b = row.types.back();
      if (row.values.size() < count || row.values.size() > count + 1) {
        throw InputError(
            located(data.file, row.line,
                    style.data_form + ", found " + std::to_string(row.values.size()) + " numbers"));
      }
      std::vector<double> values(row.values.begin(), row.values.begin() + count);
      std::optional<double> cutoff;
      if (style.fixed_cutoff) {
        cutoff = style.fixed_cutoff(values);
      } else if (row.values.size() == count + 1) {
        cutoff = row.values[count];
      }
      coeffs.set(a, b, std::move(values), cutoff);
      ++from_data;
    }
  }
  std::set<std::pair<int, int>> given;
  for (TomlTable& c : t.tables("coeffs")) {
    const auto pair = c.numbers("types", 2);
    const int a = type_index(c, "types", pair[0], types, "atom");
    const int b = type_index(c, "types", pair[1], types, "atom");
    std::vector<double> values;
    for (const StyleCoefficient& k : style.coefficients) values.push_back(read_coefficient(c, k));
    std::optional<double> cutoff;
    if (style.fixed_cutoff) {
      cutoff = style.fixed_cutoff(values);
    } else if (c.has("cutoff")) {
      cutoff = positive(c, "cutoff");
    }
    if (!given.insert({std::min(a, b), std::max(a, b)}).second)
      c.fail("coefficients for this type pair were already given", "types");
    coeffs.set(a, b, std::move(values), cutoff);
    c.finish();
  }
  if (from_data > 0) {
    notes.push_back("pair coefficients: " + counted(from_data, "entry") + " from " +
                    where(data, data.pair.line ? data.pair : data.pair_ij) +
                    (given.empty() ? ""
                                   : ", " + counted(given.size(), "entry") +
                                         " from the input (the input's win)"));
  }
  const std::vector<int> missing = coeffs.resolve(mixing, style.mixing);
  if (!missing.empty()) {
    const std::string type = std::to_string(missing.front() + 1);
    std::string keys;
    for (const StyleCoefficient& k : style.coefficients) keys += ", " + k.name + " = ...";
    t.fail("no coefficients for atom type " + type + " with itself; add {types = [" + type + ", " +
               type + "]" + keys + "} to coeffs",
           "coeffs");
  }
  t.finish();
  PairSpec spec;
  spec.style = &style;
  spec.shift = shift;
  spec.coefficients = std::move(coeffs);
  return spec;
}

// Coefficients per type: from the data file's section first (`from_data` turns a row's
// numbers into coefficients), then the input's coeffs, which win; every type must have some.
std::vector<std::vector<double>> by_type(TomlTable& t, int types, const std::string& what,
                                         const auto& read_one, const DataCoefficients& data,
                                         const CoefficientSection& section, const auto& from_data,
                                         std::vector<std::string>& notes) {
  std::vector<std::vector<double>> params(static_cast<std::size_t>(types));
  std::vector<bool> given(static_cast<std::size_t>(types), false), in_data(given);
  for (const CoefficientRow& row : section.rows) {
    params[row.types.front()] = from_data(row);
    in_data[row.types.front()] = true;
  }
  std::size_t from_input = 0;
  for (TomlTable& c : t.tables("coeffs")) {
    const int k = type_index(c, "type", c.number("type"), types, what);
    if (given[k]) c.fail("coefficients for this " + what + " type were already given", "type");
    params[k] = read_one(c, k);
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

double to_radians(double degrees) {
  return degrees * std::numbers::pi / 180.0;
}

std::vector<std::string> style_names(BondedKind kind) {
  std::vector<std::string> names;
  for (const BondedStyle* style : bonded_styles(kind)) names.push_back(style->name);
  return names;
}

// "a", "a" or "b", "a", "b" or "c": the styles a missing table could name.
std::string alternatives(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (k > 0) text += k + 1 == names.size() ? " or " : ", ";
    text += "\"" + names[k] + "\"";
  }
  return text;
}

// [forcefield.bond], [forcefield.angle] or [forcefield.dihedral]: a registered style and its
// coefficients by type, read as the style's registration describes them. A type's coeffs
// may name a style of their own (several styles in one system, as LAMMPS' hybrid); so may
// a data file's row (a hybrid section); other rows are for the table's style.
BondedSpec read_bonded(TomlTable& t, BondedKind kind, int types, const std::string& what,
                       const DataCoefficients& data, const CoefficientSection& section,
                       const char* section_name, std::vector<std::string>& notes) {
  const std::string name = t.choice("style", style_names(kind));
  check_data_style(data, section, section_name, {name}, name);
  const BondedStyle& style = *find_bonded_style(kind, name);
  BondedSpec spec;
  spec.style = &style;
  spec.style_by_type.assign(static_cast<std::size_t>(types), &style);
  spec.by_type = by_type(
      t, types, what,
      [&](TomlTable& c, int type) {
        const BondedStyle& own =
            c.has("style") ? *find_bonded_style(kind, c.choice("style", style_names(kind))) : style;
        spec.style_by_type[static_cast<std::size_t>(type)] = &own;
        std::vector<double> values;
        for (const StyleCoefficient& k : own.coefficients) {
          const double v = read_coefficient(c, k);
          values.push_back(k.degrees ? to_radians(v) : v);
        }
        return values;
      },
      data, section,
      [&](const CoefficientRow& row) {
        const BondedStyle* own = row.style.empty() ? &style : find_bonded_style(kind, row.style);
        if (own == nullptr) {
          throw InputError(located(data.file, row.line,
                                   std::string(section_name) + " row names " + what + " style '" +
                                       row.style + "', which deli does not have; deli's " + what +
                                       " styles are " + alternatives(style_names(kind))));
        }
        spec.style_by_type[static_cast<std::size_t>(row.types.front())] = own;
        expect_values(data, row, own->coefficients.size(), own->data_form);
        std::vector<double> values = row.values;
        for (std::size_t k = 0; k < values.size(); ++k) {
          const StyleCoefficient& coefficient = own->coefficients[k];
          const std::string violation = coefficient_violation(coefficient.check, values[k]);
          if (!violation.empty()) {
            throw InputError(located(data.file, row.line,
                                     section_name + std::string(": ") + coefficient.name + " " +
                                         violation + ", found " + number_text(values[k]) +
                                         " (expected " + own->data_form + ")"));
          }
          if (coefficient.degrees) values[k] = to_radians(values[k]);
        }
        return values;
      },
      notes);
  t.finish();
  return spec;
}

std::optional<BondedSpec> read_bond(std::optional<TomlTable> t, const System& system,
                                    bool rigid_bonds, const DataCoefficients& data,
                                    std::vector<std::string>& notes) {
  if (rigid_bonds) {
    if (t) t->fail("bonds are rigid rods ([constraints] bonds = \"rigid\"): remove this table");
    return std::nullopt;
  }
  if (!t) {
    if (!system.topology.bonds.empty()) {
      throw InputError(
          "the system has bonds but the input has no [forcefield.bond] table; "
          "add one with style = " +
          alternatives(style_names(BondedKind::bond)) + " and its coeffs");
    }
    return std::nullopt;
  }
  return read_bonded(*t, BondedKind::bond, system.topology.bond_types, "bond", data, data.bond,
                     "Bond Coeffs", notes);
}

std::optional<BondedSpec> read_angle(std::optional<TomlTable> t, const System& system,
                                     const DataCoefficients& data,
                                     std::vector<std::string>& notes) {
  if (!t) {
    if (!system.topology.angles.empty()) {
      throw InputError(
          "the system has angles but the input has no [forcefield.angle] table; "
          "add one with style = " +
          alternatives(style_names(BondedKind::angle)) + " and its coeffs");
    }
    return std::nullopt;
  }
  return read_bonded(*t, BondedKind::angle, system.topology.angle_types, "angle", data, data.angle,
                     "Angle Coeffs", notes);
}

std::optional<BondedSpec> read_dihedral(std::optional<TomlTable> t, const System& system,
                                        const DataCoefficients& data,
                                        std::vector<std::string>& notes) {
  if (!t) {
    if (!system.topology.dihedrals.empty()) {
      throw InputError(
          "the system has dihedrals but the input has no [forcefield.dihedral] table; "
          "add one with style = " +
          alternatives(style_names(BondedKind::dihedral)) + " and its coeffs");
    }
    return std::nullopt;
  }
  return read_bonded(*t, BondedKind::dihedral, system.topology.dihedral_types, "dihedral", data,
                     data.dihedral, "Dihedral Coeffs", notes);
}

}  // namespace

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
  spec.dihedral = read_dihedral(t->table("dihedral"), system, data, notes);
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

}  // namespace deli
