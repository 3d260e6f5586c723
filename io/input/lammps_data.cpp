#include "input/lammps_data.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace deli {

namespace {

constexpr std::array<std::string_view, 5> kAtomStyles = {"atomic", "bond", "angle", "molecular",
                                                         "full"};
constexpr char kAxisName[3] = {'x', 'y', 'z'};

bool is_atom_style(std::string_view style) {
  return std::find(kAtomStyles.begin(), kAtomStyles.end(), style) != kAtomStyles.end();
}
bool style_has_bonds(std::string_view style) {
  return style != "atomic";
}
bool style_has_angles(std::string_view style) {
  return style != "atomic" && style != "bond";
}
bool style_has_dihedrals(std::string_view style) {
  return style == "molecular" || style == "full";
}

// Column positions of one Atoms line; -1 where the style has no such column. Image flags,
// when present, are the three columns after `columns`.
struct AtomColumns {
  int columns, molecule, type, charge, x;
  const char* names;
};
AtomColumns atom_columns(std::string_view style) {
  if (style == "atomic") return {5, -1, 1, -1, 2, "id type x y z"};
  if (style == "full") return {7, 1, 2, 3, 4, "id mol type q x y z"};
  return {6, 1, 2, -1, 3, "id mol type x y z"};
}

std::string quoted(std::string_view s) {
  return "'" + std::string(s) + "'";
}

std::string_view trim(std::string_view s) {
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!s.empty() && space(s.front())) s.remove_prefix(1);
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return s;
}

void split(std::string_view s, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    const std::size_t begin = i;
    while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    if (i > begin) tokens.push_back(s.substr(begin, i - begin));
  }
}

std::string join(const std::vector<std::string_view>& tokens, std::size_t from) {
  std::string out;
  for (std::size_t i = from; i < tokens.size(); ++i) {
    if (!out.empty()) out += ' ';
    out += tokens[i];
  }
  return out;
}

// from_chars rejects a leading '+', which some generators write.
std::string_view without_plus(std::string_view s) {
  if (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}

bool parse_double(std::string_view s, double& value) {
  s = without_plus(s);
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, value);
  return !s.empty() && ec == std::errc() && ptr == end && std::isfinite(value);
}

bool parse_int(std::string_view s, std::int64_t& value) {
  s = without_plus(s);
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, value);
  return !s.empty() && ec == std::errc() && ptr == end;
}

struct Count {
  std::int64_t value = 0;
  long line = 0;  // 0 when the header does not mention it
};

struct Section {
  long line = 0;  // 0 when the file has no such section
  std::vector<std::pair<long, std::string_view>> lines;
};

struct RawAtom {
  std::int64_t id, molecule;
  int type;
  Vec3 position;
  std::array<int, 3> image;
  long line;
};

class DataReader {
 public:
  DataReader(const std::string& path, const LammpsDataOptions& options)
      : path_(path), options_(options) {}

  LammpsDataFile read();

 private:
  [[noreturn]] void fail(long line, const std::string& message) const {
    throw InputError(located(path_, line, message));
  }

  double real(std::string_view token, long line, const std::string& what) const {
    double value;
    if (!parse_double(token, value)) {
      fail(line, "expected a finite number for " + what + ", found " + quoted(token));
    }
    return value;
  }

  std::int64_t integer(std::string_view token, long line, const std::string& what) const {
    std::int64_t value;
    if (!parse_int(token, value)) {
      fail(line, "expected an integer for " + what + ", found " + quoted(token));
    }
    return value;
  }

  std::int64_t positive(std::string_view token, long line, const std::string& what) const {
    const std::int64_t value = integer(token, line, what);
    if (value < 1) fail(line, what + " must be a positive integer, found " + quoted(token));
    return value;
  }

  // A 1-based type from the file, returned 0-based.
  int type(std::string_view token, long line, const std::string& kind, const Count& count) const {
    const std::int64_t value = integer(token, line, kind);
    if (value < 1 || value > count.value) {
      fail(line, kind + " " + std::string(token) + " is outside 1.." + std::to_string(count.value) +
                     " (the header declares " + std::to_string(count.value) + " " + kind + "s)");
    }
    return static_cast<int>(value - 1);
  }

  void read_lines();
  void header_line(long line, const std::vector<std::string_view>& tokens);
  Section& section_header(long line, std::string_view content, std::string_view comment);
  std::string resolve_atom_style() const;
  void check_count(const Section& section, const char* section_name, const Count& count,
                   const char* count_name) const;
  void check_columns(long line, std::size_t found, std::size_t expected,
                     const std::string& what) const;
  std::int32_t atom_index(std::string_view token, long line, const char* section) const;

  const std::string& path_;
  const LammpsDataOptions& options_;
  std::string text_;

  Count atoms_, bonds_, angles_, dihedrals_, atom_types_, bond_types_, angle_types_,
      dihedral_types_;
  std::array<double, 3> lo_{-0.5, -0.5, -0.5}, hi_{0.5, 0.5, 0.5};  // LAMMPS' defaults
  std::array<long, 3> bounds_line_{0, 0, 0};
  Section masses_, atoms_section_, velocities_, bonds_section_, angles_section_, dihedrals_section_;
  Section pair_coeffs_, pair_ij_coeffs_, bond_coeffs_, angle_coeffs_, dihedral_coeffs_;
  std::string style_hint_;
  // the coefficient sections' comments
  std::string pair_style_, bond_style_, angle_style_, dihedral_style_;

  CoefficientSection coefficients(const Section& section, const std::string& style,
                                  const char* name, int type_columns, const Count& types,
                                  const std::string& kind) const;

  std::vector<std::int64_t> sorted_ids_;
};

void DataReader::read_lines() {
  std::ifstream in(path_, std::ios::binary);
  if (!in) fail(0, std::string("cannot open the LAMMPS data file: ") + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  text_ = std::move(buffer).str();

  std::vector<std::string_view> tokens;
  Section* current = nullptr;
  std::string_view rest = text_;
  for (long line = 1; !rest.empty(); ++line) {
    const std::size_t newline = rest.find('\n');
    std::string_view raw = rest.substr(0, newline);
    rest = newline == std::string_view::npos ? std::string_view() : rest.substr(newline + 1);
    if (line == 1) continue;  // the title

    const std::size_t hash = raw.find('#');
    const std::string_view comment =
        hash == std::string_view::npos ? std::string_view() : raw.substr(hash + 1);
    const std::string_view content = trim(raw.substr(0, hash));
    if (content.empty()) continue;

    // Header and section lines start with a number; section names start with a letter.
    if (std::isalpha(static_cast<unsigned char>(content.front()))) {
      current = &section_header(line, content, comment);
    } else if (current == nullptr) {
      split(content, tokens);
      header_line(line, tokens);
    } else {
      current->lines.emplace_back(line, content);
    }
  }
}

void DataReader::header_line(long line, const std::vector<std::string_view>& tokens) {
  std::size_t numbers = 0;
  while (numbers < tokens.size() &&
         !std::isalpha(static_cast<unsigned char>(tokens[numbers].front()))) {
    ++numbers;
  }
  const std::string keyword = join(tokens, numbers);
  if (keyword.empty()) {
    fail(line, "header line " + quoted(join(tokens, 0)) +
                   " has no keyword; expected a form such as 'N atoms' or 'lo hi xlo xhi'");
  }

  const auto expect_numbers = [&](std::size_t expected, const char* form) {
    if (numbers != expected) {
      fail(line, "header line " + quoted(keyword) + " has " + std::to_string(numbers) +
                     " values; expected '" + form + "'");
    }
  };
  const auto count = [&](Count& target) {
    expect_numbers(1, ("N " + keyword).c_str());
    if (target.line != 0) {
      fail(line, "header " + quoted(keyword) + " is given twice (first on line " +
                     std::to_string(target.line) + ")");
    }
    target.value = integer(tokens[0], line, "the number of " + keyword);
    if (target.value < 0 || target.value > std::numeric_limits<std::int32_t>::max()) {
      fail(line, "the number of " + keyword + " must be between 0 and 2147483647, found " +
                     quoted(tokens[0]));
    }
    target.line = line;
  };

  if (keyword == "atoms") return count(atoms_);
  if (keyword == "bonds") return count(bonds_);
  if (keyword == "angles") return count(angles_);
  if (keyword == "atom types") return count(atom_types_);
  if (keyword == "bond types") return count(bond_types_);
  if (keyword == "angle types") return count(angle_types_);
  if (keyword == "dihedrals") return count(dihedrals_);
  if (keyword == "dihedral types") return count(dihedral_types_);

  static constexpr std::array<std::string_view, 3> kBounds = {"xlo xhi", "ylo yhi", "zlo zhi"};
  for (int a = 0; a < 3; ++a) {
    if (keyword != kBounds[a]) continue;
    expect_numbers(2, ("lo hi " + keyword).c_str());
    if (bounds_line_[a] != 0) {
      fail(line, "header " + quoted(keyword) + " is given twice (first on line " +
                     std::to_string(bounds_line_[a]) + ")");
    }
    lo_[a] = real(tokens[0], line, std::string(1, kAxisName[a]) + "lo");
    hi_[a] = real(tokens[1], line, std::string(1, kAxisName[a]) + "hi");
    if (!(hi_[a] > lo_[a])) {
      fail(line, "box bounds " + quoted(keyword) + " are " + std::string(tokens[0]) + " " +
                     std::string(tokens[1]) + "; expected lo < hi");
    }
    bounds_line_[a] = line;
    return;
  }

  if (keyword == "xy xz yz" || keyword == "avec" || keyword == "bvec" || keyword == "cvec" ||
      keyword == "abc origin") {
    fail(line, "found the triclinic box header " + quoted(keyword) +
                   "; deli boxes are orthorhombic (expected only xlo xhi, ylo yhi, zlo zhi)");
  }

  static const std::vector<std::string> kUnsupportedCounts = {"impropers",
                                                              "improper types",
                                                              "extra bond per atom",
                                                              "extra angle per atom",
                                                              "extra dihedral per atom",
                                                              "extra improper per atom",
                                                              "extra special per atom",
                                                              "ellipsoids",
                                                              "lines",
                                                              "triangles",
                                                              "bodies"};
  if (std::find(kUnsupportedCounts.begin(), kUnsupportedCounts.end(), keyword) !=
      kUnsupportedCounts.end()) {
    expect_numbers(1, ("N " + keyword).c_str());
    if (integer(tokens[0], line, "the number of " + keyword) != 0) {
      fail(line, "the header declares " + std::string(tokens[0]) + " " + keyword +
                     "; deli does not support " + keyword + " (expected 0 or no such line)");
    }
    return;
  }

  static const std::vector<std::string> kKnown = {
      "atoms",       "bonds",          "angles",  "dihedrals", "atom types", "bond types",
      "angle types", "dihedral types", "xlo xhi", "ylo yhi",   "zlo zhi"};
  std::string message = "unknown header line " + quoted(keyword);
  const std::string suggestion = closest_match(keyword, kKnown);
  if (!suggestion.empty()) message += "; did you mean " + quoted(suggestion) + "?";
  message +=
      "; expected one of 'N atoms', 'N bonds', 'N angles', 'N dihedrals', 'N atom types', "
      "'N bond types', 'N angle types', 'N dihedral types', 'lo hi xlo xhi' (and ylo yhi, zlo "
      "zhi)";
  fail(line, message);
}

Section& DataReader::section_header(long line, std::string_view content, std::string_view comment) {
  std::vector<std::string_view> tokens;
  split(content, tokens);
  const std::string name = join(tokens, 0);

  static constexpr std::array<std::pair<std::string_view, Section DataReader::*>, 11> kSections = {{
      {"Masses", &DataReader::masses_},
      {"Atoms", &DataReader::atoms_section_},
      {"Velocities", &DataReader::velocities_},
      {"Bonds", &DataReader::bonds_section_},
      {"Angles", &DataReader::angles_section_},
      {"Dihedrals", &DataReader::dihedrals_section_},
      {"Pair Coeffs", &DataReader::pair_coeffs_},
      {"PairIJ Coeffs", &DataReader::pair_ij_coeffs_},
      {"Bond Coeffs", &DataReader::bond_coeffs_},
      {"Angle Coeffs", &DataReader::angle_coeffs_},
      {"Dihedral Coeffs", &DataReader::dihedral_coeffs_},
  }};
  for (const auto& [section_name, member] : kSections) {
    if (name != section_name) continue;
    Section& section = this->*member;
    if (section.line != 0) {
      fail(line, "section " + quoted(name) + " appears twice (first on line " +
                     std::to_string(section.line) + ")");
    }
    section.line = line;
    std::vector<std::string_view> hint;
    split(comment, hint);
    const std::string first = hint.empty() ? "" : std::string(hint.front());
    if (name == "Atoms") style_hint_ = first;
    if (name == "Pair Coeffs" || name == "PairIJ Coeffs") pair_style_ = first;
    if (name == "Bond Coeffs") bond_style_ = first;
    if (name == "Angle Coeffs") angle_style_ = first;
    if (name == "Dihedral Coeffs") dihedral_style_ = first;
    return section;
  }

  if (name.ends_with("Coeffs")) {
    fail(line, "found section " + quoted(name) +
                   "; deli reads Pair, PairIJ, Bond, Angle and Dihedral Coeffs (no impropers): "
                   "remove this section");
  }
  static const std::vector<std::string> kUnsupported = {"Impropers", "Ellipsoids", "Lines",
                                                        "Triangles", "Bodies"};
  if (std::find(kUnsupported.begin(), kUnsupported.end(), name) != kUnsupported.end()) {
    fail(line, "found section " + quoted(name) + "; deli does not support " + name +
                   " (expected Masses, Atoms, Velocities, Bonds, Angles or Dihedrals)");
  }
  std::string message = "unknown section " + quoted(name);
  const std::string suggestion =
      closest_match(name, {"Masses", "Atoms", "Velocities", "Bonds", "Angles", "Dihedrals"});
  if (!suggestion.empty()) message += "; did you mean " + quoted(suggestion) + "?";
  message +=
      "; deli reads Masses, Atoms, Velocities, Bonds, Angles, Dihedrals and their Pair, PairIJ, "
      "Bond, Angle and Dihedral Coeffs";
  fail(line, message);
}

std::string DataReader::resolve_atom_style() const {
  const std::string& option = options_.atom_style;
  if (!option.empty() && !is_atom_style(option)) {
    fail(0, "atom style option " + quoted(option) +
                " is not supported; expected atomic, bond, angle, molecular or full");
  }
  if (!style_hint_.empty()) {
    if (!is_atom_style(style_hint_)) {
      fail(atoms_section_.line, "the Atoms section is marked '# " + style_hint_ +
                                    "'; deli reads atom styles atomic, bond, angle, molecular "
                                    "and full");
    }
    if (!option.empty() && option != style_hint_) {
      fail(atoms_section_.line, "the Atoms section is marked '# " + style_hint_ +
                                    "' but the atom style option is " + quoted(option) +
                                    "; make them agree");
    }
    return style_hint_;
  }
  if (!option.empty()) return option;
  if (atoms_section_.lines.empty()) return "atomic";

  const auto& [line, content] = atoms_section_.lines.front();
  std::vector<std::string_view> tokens;
  split(content, tokens);
  switch (tokens.size()) {
    case 5:
    case 8:
      return "atomic";
    case 6:
    case 9:
      return "molecular";
    case 7:
    case 10:
      return "full";
    default:
      fail(line, "cannot infer the atom style from an Atoms line with " +
                     std::to_string(tokens.size()) +
                     " columns; expected 5 or 8 (atomic), 6 or 9 (molecular) or 7 or 10 (full), "
                     "or name the style with 'Atoms # style'");
  }
}

void DataReader::check_count(const Section& section, const char* section_name, const Count& count,
                             const char* count_name) const {
  if (section.line == 0) {
    if (count.value > 0) {
      fail(count.line, "the header declares " + std::to_string(count.value) + " " + count_name +
                           " but the file has no " + section_name + " section");
    }
    return;
  }
  if (static_cast<std::int64_t>(section.lines.size()) != count.value) {
    std::string declared = count.line == 0
                               ? "the header declares no " + std::string(count_name)
                               : "the header (line " + std::to_string(count.line) + ") declares " +
                                     std::to_string(count.value) + " " + count_name;
    fail(section.line, std::string(section_name) + " section has " +
                           std::to_string(section.lines.size()) + " lines but " + declared);
  }
}

void DataReader::check_columns(long line, std::size_t found, std::size_t expected,
                               const std::string& what) const {
  if (found != expected) {
    fail(line, "line has " + std::to_string(found) + " columns; expected " +
                   std::to_string(expected) + " (" + what + ")");
  }
}

std::int32_t DataReader::atom_index(std::string_view token, long line, const char* section) const {
  const std::int64_t id = integer(token, line, std::string("an atom id in ") + section);
  const auto it = std::lower_bound(sorted_ids_.begin(), sorted_ids_.end(), id);
  if (it == sorted_ids_.end() || *it != id) {
    fail(line, std::string(section) + " line names atom id " + std::string(token) +
                   ", which is not in the Atoms section");
  }
  return static_cast<std::int32_t>(it - sorted_ids_.begin());
}

CoefficientSection DataReader::coefficients(const Section& section, const std::string& style,
                                            const char* name, int type_columns, const Count& types,
                                            const std::string& kind) const {
  CoefficientSection out;
  out.line = section.line;
  out.style = style;
  std::vector<std::string_view> tokens;
  std::set<std::vector<int>> seen;
  for (const auto& [line, content] : section.lines) {
    split(content, tokens);
    if (tokens.size() <= static_cast<std::size_t>(type_columns)) {
      fail(line, std::string(name) + " line has " + std::to_string(tokens.size()) +
                     " columns; expected " + (type_columns == 1 ? "a type" : "two types") +
                     " and the coefficients");
    }
    CoefficientRow row;
    row.line = line;
    for (int k = 0; k < type_columns; ++k) row.types.push_back(type(tokens[k], line, kind, types));
    // A hybrid style's row names its style after the types (LAMMPS' read_data form).
    std::size_t first_value = static_cast<std::size_t>(type_columns);
    if (std::isalpha(static_cast<unsigned char>(tokens[first_value].front()))) {
      row.style = tokens[first_value++];
    }
    for (std::size_t k = first_value; k < tokens.size(); ++k) {
      row.values.push_back(real(tokens[k], line, std::string("a coefficient in ") + name));
    }
    if (!seen.insert(row.types).second) {
      fail(line, std::string(name) + " gives type " + std::string(tokens[0]) +
                     (type_columns == 2 ? " " + std::string(tokens[1]) : "") + " twice");
    }
    out.rows.push_back(std::move(row));
  }
  return out;
}

LammpsDataFile DataReader::read() {
  read_lines();
  if (atoms_.value == 0) {
    fail(atoms_.line, atoms_.line == 0
                          ? "the file has no 'N atoms' header line: it is empty or not a LAMMPS "
                            "data file (write one with LAMMPS write_data or deli write-data)"
                          : "the file declares 0 atoms: a run needs atoms");
  }

  LammpsDataFile result;
  result.path = path_;
  result.atom_style = resolve_atom_style();
  result.pair = coefficients(pair_coeffs_, pair_style_, "Pair Coeffs", 1, atom_types_, "atom type");
  result.pair_ij =
      coefficients(pair_ij_coeffs_, pair_style_, "PairIJ Coeffs", 2, atom_types_, "atom type");
  result.bond = coefficients(bond_coeffs_, bond_style_, "Bond Coeffs", 1, bond_types_, "bond type");
  result.angle =
      coefficients(angle_coeffs_, angle_style_, "Angle Coeffs", 1, angle_types_, "angle type");
  result.dihedral = coefficients(dihedral_coeffs_, dihedral_style_, "Dihedral Coeffs", 1,
                                 dihedral_types_, "dihedral type");
  const std::string& style = result.atom_style;
  if (!style_has_bonds(style) && (bonds_.value > 0 || bonds_section_.line != 0)) {
    fail(bonds_section_.line != 0 ? bonds_section_.line : bonds_.line,
         "atom style '" + style +
             "' has no bonds; use bond, molecular or full for a file "
             "with bonds");
  }
  if (!style_has_angles(style) && (angles_.value > 0 || angles_section_.line != 0)) {
    fail(angles_section_.line != 0 ? angles_section_.line : angles_.line,
         "atom style '" + style +
             "' has no angles; use angle, molecular or full for a file "
             "with angles");
  }
  check_count(atoms_section_, "Atoms", atoms_, "atoms");
  if (velocities_.line != 0) check_count(velocities_, "Velocities", atoms_, "atoms");
  check_count(bonds_section_, "Bonds", bonds_, "bonds");
  if (!style_has_dihedrals(style) && (dihedrals_.value > 0 || dihedrals_section_.line != 0)) {
    fail(dihedrals_section_.line != 0 ? dihedrals_section_.line : dihedrals_.line,
         "atom style '" + style +
             "' has no dihedrals; use molecular or full for a file with dihedrals");
  }
  check_count(angles_section_, "Angles", angles_, "angles");
  check_count(dihedrals_section_, "Dihedrals", dihedrals_, "dihedrals");

  std::vector<std::string_view> tokens;

  // Masses, by 0-based type.
  std::vector<double> masses(atom_types_.value, 0.0);
  std::vector<long> mass_line(atom_types_.value, 0);
  for (const auto& [line, content] : masses_.lines) {
    split(content, tokens);
    check_columns(line, tokens.size(), 2, "type mass");
    const int t = type(tokens[0], line, "atom type", atom_types_);
    if (mass_line[t] != 0) {
      fail(line, "Masses gives atom type " + std::to_string(t + 1) + " twice (first on line " +
                     std::to_string(mass_line[t]) + ")");
    }
    masses[t] = real(tokens[1], line, "the mass of atom type " + std::to_string(t + 1));
    if (!(masses[t] > 0)) {
      fail(line, "the mass of atom type " + std::to_string(t + 1) + " is " +
                     std::string(tokens[1]) + "; expected a positive mass");
    }
    mass_line[t] = line;
  }

  // Atoms.
  const AtomColumns columns = atom_columns(style);
  std::vector<RawAtom> raw;
  raw.reserve(atoms_section_.lines.size());
  for (const auto& [line, content] : atoms_section_.lines) {
    split(content, tokens);
    const std::size_t n = columns.columns;
    if (tokens.size() != n && tokens.size() != n + 3) {
      fail(line, "Atoms line has " + std::to_string(tokens.size()) + " columns; atom style '" +
                     style + "' expects " + std::to_string(n) + " (" + columns.names + ") or " +
                     std::to_string(n + 3) + " (" + columns.names + " ix iy iz)");
    }
    RawAtom atom{};
    atom.line = line;
    atom.id = positive(tokens[0], line, "the atom id");
    const std::string who = "atom " + std::to_string(atom.id);
    if (columns.molecule >= 0) {
      atom.molecule = integer(tokens[columns.molecule], line, "the molecule id of " + who);
      if (atom.molecule < 0) {
        fail(line, "the molecule id of " + who + " is " + std::to_string(atom.molecule) +
                       "; expected 0 (no molecule) or a positive id");
      }
    }
    atom.type = type(tokens[columns.type], line, "atom type", atom_types_);
    if (columns.charge >= 0) {
      const double q = real(tokens[columns.charge], line, "the charge of " + who);
      if (q != 0.0) {
        fail(line, who + " has charge " + std::string(tokens[columns.charge]) +
                       "; deli has no electrostatics, so every charge must be 0");
      }
    }
    for (int a = 0; a < 3; ++a) {
      atom.position[a] =
          real(tokens[columns.x + a], line, std::string(1, kAxisName[a]) + " of " + who);
      if (tokens.size() == n + 3) {
        const std::int64_t image =
            integer(tokens[n + a], line, std::string("image flag i") + kAxisName[a] + " of " + who);
        if (image < std::numeric_limits<int>::min() || image > std::numeric_limits<int>::max()) {
          fail(line, "image flag i" + std::string(1, kAxisName[a]) + " of " + who + " is " +
                         std::string(tokens[n + a]) + "; expected a 32-bit integer");
        }
        atom.image[a] = static_cast<int>(image);
      }
    }
    // Like LAMMPS' read_data, an atom outside a periodic box is mapped back into it with its
    // image flag counting the crossings, so that its unwrapped position is kept; a count
    // beyond a 32-bit image flag cannot be (found by fuzzing: the cast overflowed).
    for (int a = 0; a < 3; ++a) {
      if (!options_.periodic[a]) continue;
      const double crossings =
          std::floor((atom.position[a] - lo_[a]) / (hi_[a] - lo_[a])) + atom.image[a];
      if (!(std::abs(crossings) <= std::numeric_limits<int>::max())) {
        fail(line, std::string(1, kAxisName[a]) + " of " + who + " is " +
                       std::string(tokens[columns.x + a]) +
                       ", so far outside the periodic box that its image flag would not fit in "
                       "32 bits; expected a position in or near the box");
      }
    }
    Box({lo_[0], lo_[1], lo_[2]}, {hi_[0], hi_[1], hi_[2]}, options_.periodic)
        .wrap(atom.position, atom.image);
    if (mass_line.empty() || mass_line[atom.type] == 0) {
      fail(line, who + " has atom type " + std::to_string(atom.type + 1) +
                     ", which has no entry in the Masses section");
    }
    raw.push_back(atom);
  }
  std::sort(raw.begin(), raw.end(), [](const RawAtom& a, const RawAtom& b) { return a.id < b.id; });
  for (std::size_t i = 1; i < raw.size(); ++i) {
    if (raw[i].id == raw[i - 1].id) {
      const auto [first, second] = std::minmax(raw[i - 1].line, raw[i].line);
      fail(second, "atom id " + std::to_string(raw[i].id) + " is used twice (first on line " +
                       std::to_string(first) + "); atom ids must be unique");
    }
  }

  System& system = result.system;
  system.box = Box({lo_[0], lo_[1], lo_[2]}, {hi_[0], hi_[1], hi_[2]}, options_.periodic);
  system.atom_types.resize(atom_types_.value);
  for (std::size_t t = 0; t < masses.size(); ++t) {
    if (mass_line[t] != 0) system.atom_types[t].mass = masses[t];
  }
  Particles& p = system.particles;
  p.resize(raw.size());
  sorted_ids_.resize(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    p.position[i] = raw[i].position;
    p.velocity[i] = Vec3{};
    p.mass[i] = system.atom_types[raw[i].type].mass;
    p.radius[i] = system.atom_types[raw[i].type].radius;
    p.type[i] = raw[i].type;
    p.id[i] = raw[i].id;
    p.molecule[i] = raw[i].molecule;
    p.image[i] = raw[i].image;
    sorted_ids_[i] = raw[i].id;
  }

  // Velocities.
  result.has_velocities = velocities_.line != 0;
  std::vector<long> velocity_line(raw.size(), 0);
  for (const auto& [line, content] : velocities_.lines) {
    split(content, tokens);
    check_columns(line, tokens.size(), 4, "id vx vy vz");
    const std::int32_t i = atom_index(tokens[0], line, "Velocities");
    if (velocity_line[i] != 0) {
      fail(line, "Velocities gives atom " + std::string(tokens[0]) + " twice (first on line " +
                     std::to_string(velocity_line[i]) + ")");
    }
    velocity_line[i] = line;
    for (int a = 0; a < 3; ++a) {
      p.velocity[i][a] =
          real(tokens[1 + a], line,
               std::string("v") + kAxisName[a] + " of atom " + std::string(tokens[0]));
    }
  }

  // Bonds and angles.
  Topology& topology = system.topology;
  topology.bond_types = static_cast<int>(bond_types_.value);
  topology.angle_types = static_cast<int>(angle_types_.value);
  topology.bonds.reserve(bonds_section_.lines.size());
  for (const auto& [line, content] : bonds_section_.lines) {
    split(content, tokens);
    check_columns(line, tokens.size(), 4, "id type atom1 atom2");
    positive(tokens[0], line, "the bond id");
    Bond bond;
    bond.type = type(tokens[1], line, "bond type", bond_types_);
    bond.i = atom_index(tokens[2], line, "Bonds");
    bond.j = atom_index(tokens[3], line, "Bonds");
    if (bond.i == bond.j) {
      fail(line, "bond " + std::string(tokens[0]) + " joins atom " + std::string(tokens[2]) +
                     " to itself; expected two different atoms");
    }
    topology.bonds.push_back(bond);
  }
  topology.angles.reserve(angles_section_.lines.size());
  for (const auto& [line, content] : angles_section_.lines) {
    split(content, tokens);
    check_columns(line, tokens.size(), 5, "id type atom1 atom2 atom3");
    positive(tokens[0], line, "the angle id");
    Angle angle;
    angle.type = type(tokens[1], line, "angle type", angle_types_);
    angle.i = atom_index(tokens[2], line, "Angles");
    angle.j = atom_index(tokens[3], line, "Angles");
    angle.k = atom_index(tokens[4], line, "Angles");
    if (angle.i == angle.j || angle.j == angle.k || angle.i == angle.k) {
      fail(line, "angle " + std::string(tokens[0]) + " names atoms " + std::string(tokens[2]) +
                     " " + std::string(tokens[3]) + " " + std::string(tokens[4]) +
                     "; expected three different atoms");
    }
    topology.angles.push_back(angle);
  }
  topology.dihedral_types = static_cast<int>(dihedral_types_.value);
  topology.dihedrals.reserve(dihedrals_section_.lines.size());
  for (const auto& [line, content] : dihedrals_section_.lines) {
    split(content, tokens);
    check_columns(line, tokens.size(), 6, "id type atom1 atom2 atom3 atom4");
    positive(tokens[0], line, "the dihedral id");
    Dihedral dihedral;
    dihedral.type = type(tokens[1], line, "dihedral type", dihedral_types_);
    dihedral.i = atom_index(tokens[2], line, "Dihedrals");
    dihedral.j = atom_index(tokens[3], line, "Dihedrals");
    dihedral.k = atom_index(tokens[4], line, "Dihedrals");
    dihedral.l = atom_index(tokens[5], line, "Dihedrals");
    const std::array<std::int32_t, 4> atoms{dihedral.i, dihedral.j, dihedral.k, dihedral.l};
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        if (atoms[a] != atoms[b]) continue;
        fail(line, "dihedral " + std::string(tokens[0]) + " names atoms " + std::string(tokens[2]) +
                       " " + std::string(tokens[3]) + " " + std::string(tokens[4]) + " " +
                       std::string(tokens[5]) + "; expected four different atoms");
      }
    }
    topology.dihedrals.push_back(dihedral);
  }
  return result;
}

[[gnu::format(printf, 2, 3)]] void append(std::string& out, const char* format, ...) {
  char buffer[256];
  std::va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  if (n < static_cast<int>(sizeof buffer)) {
    out.append(buffer, static_cast<std::size_t>(n));
    return;
  }
  const std::size_t size = out.size();
  out.resize(size + static_cast<std::size_t>(n) + 1);
  va_start(args, format);
  std::vsnprintf(out.data() + size, static_cast<std::size_t>(n) + 1, format, args);
  va_end(args);
  out.resize(size + static_cast<std::size_t>(n));
}

}  // namespace

LammpsDataFile read_lammps_data(const std::string& path, const LammpsDataOptions& options) {
  return DataReader(path, options).read();
}

void write_lammps_data(const System& system, const std::string& path, const std::string& atom_style,
                       const std::string& title) {
  const auto fail = [&](const std::string& message) {
    throw InputError(located(path, 0, message));
  };
  if (!is_atom_style(atom_style)) {
    fail("cannot write atom style " + quoted(atom_style) +
         "; expected atomic, bond, angle, molecular or full");
  }
  const Particles& p = system.particles;
  const Topology& topology = system.topology;
  if (!style_has_bonds(atom_style) && !topology.bonds.empty()) {
    fail("the system has bonds, which atom style '" + atom_style +
         "' cannot hold; use bond, molecular or full");
  }
  if (!style_has_angles(atom_style) && !topology.angles.empty()) {
    fail("the system has angles, which atom style '" + atom_style +
         "' cannot hold; use angle, molecular or full");
  }
  if (!style_has_dihedrals(atom_style) && !topology.dihedrals.empty()) {
    fail("the system has dihedrals, which atom style '" + atom_style +
         "' cannot hold; use molecular or full");
  }

  // Types beyond those declared still need a Masses line, or read_data rejects the file.
  std::size_t atom_types = system.atom_types.size();
  for (int t : p.type) atom_types = std::max(atom_types, static_cast<std::size_t>(t) + 1);
  int bond_types = topology.bond_types;
  for (const Bond& b : topology.bonds) bond_types = std::max(bond_types, b.type + 1);
  int angle_types = topology.angle_types;
  for (const Angle& a : topology.angles) angle_types = std::max(angle_types, a.type + 1);
  int dihedral_types = topology.dihedral_types;
  for (const Dihedral& d : topology.dihedrals)
    dihedral_types = std::max(dihedral_types, d.type + 1);

  std::string out;
  std::string first_line = title;
  std::replace(first_line.begin(), first_line.end(), '\n', ' ');
  std::replace(first_line.begin(), first_line.end(), '\r', ' ');
  out += first_line + "\n\n";

  const bool bonds = style_has_bonds(atom_style), angles = style_has_angles(atom_style);
  // Written only when there are some, so that files without dihedrals stay as they were.
  const bool dihedrals = !topology.dihedrals.empty() || dihedral_types > 0;
  append(out, "%zu atoms\n", p.size());
  if (bonds) append(out, "%zu bonds\n", topology.bonds.size());
  if (angles) append(out, "%zu angles\n", topology.angles.size());
  if (dihedrals) append(out, "%zu dihedrals\n", topology.dihedrals.size());
  append(out, "\n%zu atom types\n", atom_types);
  if (bonds) append(out, "%d bond types\n", bond_types);
  if (angles) append(out, "%d angle types\n", angle_types);
  if (dihedrals) append(out, "%d dihedral types\n", dihedral_types);
  out += '\n';
  const Box& box = system.box;
  static constexpr std::array<const char*, 3> kBounds = {"xlo xhi", "ylo yhi", "zlo zhi"};
  for (int a = 0; a < 3; ++a) {
    append(out, "%.17g %.17g %s\n", box.lo()[a], box.hi()[a], kBounds[a]);
  }

  if (atom_types > 0) {
    out += "\nMasses\n\n";
    for (std::size_t t = 0; t < atom_types; ++t) {
      double mass = 1.0;
      if (t < system.atom_types.size()) {
        mass = system.atom_types[t].mass;
      } else {
        const auto it = std::find(p.type.begin(), p.type.end(), static_cast<int>(t));
        if (it != p.type.end()) mass = p.mass[it - p.type.begin()];
      }
      append(out, "%zu %.17g\n", t + 1, mass);
    }
  }

  if (p.size() > 0) {
    append(out, "\nAtoms # %s\n\n", atom_style.c_str());
    for (std::size_t i = 0; i < p.size(); ++i) {
      // Readers (deli's included) want periodic coordinates inside [lo, hi). Atoms already
      // inside are left untouched so that the round trip stays bit-exact.
      Vec3 x = p.position[i];
      std::array<int, 3> image = p.image[i];
      bool outside = false;
      for (int a = 0; a < 3; ++a) {
        outside = outside || (box.periodic(a) && !(x[a] >= box.lo()[a] && x[a] < box.hi()[a]));
      }
      if (outside) box.wrap(x, image);
      const long long id = p.id[i], molecule = p.molecule[i];
      const int type = p.type[i] + 1;
      if (atom_style == "atomic") {
        append(out, "%lld %d", id, type);
      } else if (atom_style == "full") {
        append(out, "%lld %lld %d 0", id, molecule, type);
      } else {
        append(out, "%lld %lld %d", id, molecule, type);
      }
      append(out, " %.17g %.17g %.17g %d %d %d\n", x.x, x.y, x.z, image[0], image[1], image[2]);
    }

    out += "\nVelocities\n\n";
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec3& v = p.velocity[i];
      append(out, "%lld %.17g %.17g %.17g\n", static_cast<long long>(p.id[i]), v.x, v.y, v.z);
    }
  }

  if (!topology.bonds.empty()) {
    out += "\nBonds\n\n";
    for (std::size_t b = 0; b < topology.bonds.size(); ++b) {
      const Bond& bond = topology.bonds[b];
      append(out, "%zu %d %lld %lld\n", b + 1, bond.type + 1, static_cast<long long>(p.id[bond.i]),
             static_cast<long long>(p.id[bond.j]));
    }
  }
  if (!topology.angles.empty()) {
    out += "\nAngles\n\n";
    for (std::size_t a = 0; a < topology.angles.size(); ++a) {
      const Angle& angle = topology.angles[a];
      append(out, "%zu %d %lld %lld %lld\n", a + 1, angle.type + 1,
             static_cast<long long>(p.id[angle.i]), static_cast<long long>(p.id[angle.j]),
             static_cast<long long>(p.id[angle.k]));
    }
  }
  if (!topology.dihedrals.empty()) {
    out += "\nDihedrals\n\n";
    for (std::size_t d = 0; d < topology.dihedrals.size(); ++d) {
      const Dihedral& dihedral = topology.dihedrals[d];
      append(out, "%zu %d %lld %lld %lld %lld\n", d + 1, dihedral.type + 1,
             static_cast<long long>(p.id[dihedral.i]), static_cast<long long>(p.id[dihedral.j]),
             static_cast<long long>(p.id[dihedral.k]), static_cast<long long>(p.id[dihedral.l]));
    }
  }

  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) fail(std::string("cannot open for writing: ") + std::strerror(errno));
  file << out;
  file.flush();
  if (!file) fail(std::string("cannot write the LAMMPS data file: ") + std::strerror(errno));
}

}  // namespace deli
