#pragma once

#include <toml++/toml.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

namespace deli {

// A TOML table read with its place in the file: every getter checks the type, every error
// names file:line, the key's full path, what was found and what is expected, and
// finish() rejects keys that were never asked for (with a did-you-mean).
class TomlTable {
 public:
  TomlTable(const toml::table& table, std::string file, std::string path);

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  long line() const;
  bool has(const std::string& key) const;

  double number(const std::string& key, std::optional<double> fallback = std::nullopt);
  std::int64_t integer(const std::string& key, std::optional<std::int64_t> fallback = std::nullopt);
  bool boolean(const std::string& key, std::optional<bool> fallback = std::nullopt);
  std::string string(const std::string& key, std::optional<std::string> fallback = std::nullopt);
  // A string that must be one of `choices`.
  std::string choice(const std::string& key, const std::vector<std::string>& choices,
                     std::optional<std::string> fallback = std::nullopt);
  std::vector<double> numbers(const std::string& key, std::size_t size);
  std::optional<TomlTable> table(const std::string& key);
  // An array of tables (`coeffs = [{...}, {...}]`).
  std::vector<TomlTable> tables(const std::string& key);

  // Throws for keys never asked for; call after reading everything.
  void finish() const;

  // An error located at this table (key: at that key's value).
  [[noreturn]] void fail(const std::string& message, const std::string& key = "") const;

 private:
  const toml::node& require(const std::string& key) const;
  std::string key_path(const std::string& key) const;

  const toml::table* table_;
  std::string file_, path_;
  mutable std::set<std::string> used_;
};

// A number that must be positive and finite (`fallback` when the key is absent, if given).
double positive(TomlTable& t, const std::string& key, std::optional<double> fallback = {});

}  // namespace deli
