#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace deli {

// Something the user wrote is wrong. The message names the place (file:line or key,
// atom id) and what to do; the CLI prints it as is.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The simulation cannot go on (a bond stretched past FENE's limit, a solver that did
// not converge). The message names the step and the particles involved.
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "file:line: message" (line omitted when 0).
std::string located(const std::string& file, long line, const std::string& message);

// The closest of `candidates` to `word`, or "" when nothing is close enough to suggest.
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace deli
