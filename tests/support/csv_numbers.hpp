#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace deli::testing {

// The rows of a CSV file's text after its header, each as its numbers.
inline std::vector<std::vector<double>> csv_numbers(const std::string& csv) {
  std::vector<std::vector<double>> rows;
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);  // header
  while (std::getline(lines, line)) {
    std::vector<double> row;
    std::istringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) row.push_back(std::stod(field));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace deli::testing
