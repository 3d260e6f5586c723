#include "input/toml_table.hpp"

#include <cmath>

#include "core/error.hpp"

namespace deli {

namespace {
std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a number";
    case toml::node_type::boolean:
      return "a boolean";
    default:
      return "a date or time";
  }
}
// TOML accepts nan and inf; no quantity of a run may be either (NaN passes every `< 0`
// check, so this is the one place that keeps it out).
std::string not_finite(double v) {
  return std::string("expected a finite number, found ") + (std::isnan(v) ? "nan" : "inf") +
         "; give a finite value";
}
}  // namespace

TomlTable::TomlTable(const toml::table& table, std::string file, std::string path)
    : table_(&table), file_(std::move(file)), path_(std::move(path)) {}

long TomlTable::line() const {
  return static_cast<long>(table_->source().begin.line);
}

bool TomlTable::has(const std::string& key) const {
  used_.insert(key);
  return table_->contains(key);
}

std::string TomlTable::key_path(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void TomlTable::fail(const std::string& message, const std::string& key) const {
  long where = line();
  if (!key.empty()) {
    if (const toml::node* node = table_->get(key))
      where = static_cast<long>(node->source().begin.line);
  }
  const std::string subject =
      key.empty() ? (path_.empty() ? "" : "[" + path_ + "]: ") : "'" + key_path(key) + "': ";
  throw InputError(located(file_, where, subject + message));
}

const toml::node& TomlTable::require(const std::string& key) const {
  used_.insert(key);
  const toml::node* node = table_->get(key);
  if (!node) {
    std::vector<std::string> present;
    for (const auto& [name, value] : *table_) present.emplace_back(name.str());
    const std::string guess = closest_match(key, present);
    fail("missing required key '" + key_path(key) + "'" +
         (guess.empty() ? "" : "; found '" + guess + "': a misspelling of '" + key + "'?"));
  }
  return *node;
}

double TomlTable::number(const std::string& key, std::optional<double> fallback) {
  used_.insert(key);
  if (!table_->contains(key) && fallback) return *fallback;
  const toml::node& node = require(key);
  if (auto v = node.value<double>(); v && (node.is_floating_point() || node.is_integer())) {
    if (!std::isfinite(*v)) fail(not_finite(*v), key);
    return *v;
  }
  fail("expected a number, found " + type_name(node), key);
}

std::int64_t TomlTable::integer(const std::string& key, std::optional<std::int64_t> fallback) {
  used_.insert(key);
  if (!table_->contains(key) && fallback) return *fallback;
  const toml::node& node = require(key);
  if (node.is_integer()) return *node.value<std::int64_t>();
  fail("expected an integer, found " + type_name(node), key);
}

bool TomlTable::boolean(const std::string& key, std::optional<bool> fallback) {
  used_.insert(key);
  if (!table_->contains(key) && fallback) return *fallback;
  const toml::node& node = require(key);
  if (node.is_boolean()) return *node.value<bool>();
  fail("expected true or false, found " + type_name(node), key);
}

std::string TomlTable::string(const std::string& key, std::optional<std::string> fallback) {
  used_.insert(key);
  if (!table_->contains(key) && fallback) return *fallback;
  const toml::node& node = require(key);
  if (node.is_string()) return *node.value<std::string>();
  fail("expected a string, found " + type_name(node), key);
}

std::string TomlTable::choice(const std::string& key, const std::vector<std::string>& choices,
                              std::optional<std::string> fallback) {
  const std::string value = string(key, std::move(fallback));
  for (const std::string& c : choices) {
    if (c == value) return value;
  }
  std::string list;
  for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + ("\"" + c + "\"");
  const std::string guess = closest_match(value, choices);
  fail("unknown value \"" + value + "\"; expected one of " + list +
           (guess.empty() ? "" : " (did you mean \"" + guess + "\"?)"),
       key);
}

std::vector<double> TomlTable::numbers(const std::string& key, std::size_t size) {
  const toml::node& node = require(key);
  const toml::array* array = node.as_array();
  if (!array || array->size() != size) {
    fail("expected an array of " + std::to_string(size) + " numbers, found " +
             (array ? "an array of " + std::to_string(array->size()) : type_name(node)),
         key);
  }
  std::vector<double> values;
  for (const toml::node& element : *array) {
    auto v = element.value<double>();
    if (!v || !(element.is_floating_point() || element.is_integer())) {
      fail("expected numbers, found " + type_name(element), key);
    }
    if (!std::isfinite(*v)) {
      fail("element " + std::to_string(values.size() + 1) + ": " + not_finite(*v), key);
    }
    values.push_back(*v);
  }
  return values;
}

std::optional<TomlTable> TomlTable::table(const std::string& key) {
  used_.insert(key);
  const toml::node* node = table_->get(key);
  if (!node) return std::nullopt;
  if (!node->is_table()) fail("expected a table, found " + type_name(*node), key);
  return TomlTable(*node->as_table(), file_, key_path(key));
}

std::vector<TomlTable> TomlTable::tables(const std::string& key) {
  used_.insert(key);
  std::vector<TomlTable> result;
  const toml::node* node = table_->get(key);
  if (!node) return result;
  const toml::array* array = node->as_array();
  if (!array) fail("expected an array of tables ([{...}, ...]), found " + type_name(*node), key);
  for (std::size_t k = 0; k < array->size(); ++k) {
    const toml::node& element = *array->get(k);
    if (!element.is_table()) fail("element " + std::to_string(k + 1) + " is not a table", key);
    result.emplace_back(*element.as_table(), file_,
                        key_path(key) + "[" + std::to_string(k + 1) + "]");
  }
  return result;
}

void TomlTable::finish() const {
  for (const auto& [key, node] : *table_) {
    const std::string name(key.str());
    if (used_.count(name)) continue;
    std::vector<std::string> known(used_.begin(), used_.end());
    const std::string guess = closest_match(name, known);
    std::string expected;
    for (const std::string& k : known) expected += (expected.empty() ? "" : ", ") + k;
    throw InputError(located(file_, static_cast<long>(node.source().begin.line),
                             "unknown key '" + key_path(name) + "'" +
                                 (guess.empty() ? "" : "; did you mean '" + guess + "'?") +
                                 " (keys allowed here: " + expected + ")"));
  }
}

double positive(TomlTable& t, const std::string& key, std::optional<double> fallback) {
  const double v = t.number(key, fallback);
  if (!(v > 0.0) || !std::isfinite(v))
    t.fail("must be a positive number, found " + std::to_string(v), key);
  return v;
}

}  // namespace deli
