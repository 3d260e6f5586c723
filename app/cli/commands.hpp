#pragma once

#include <string>
#include <vector>

namespace deli {

// Each returns the process exit status; errors are thrown (InputError, SimulationError).
int command_run(const std::vector<std::string>& args);
int command_write_data(const std::vector<std::string>& args);
int command_validate(const std::vector<std::string>& args);
int command_info(const std::vector<std::string>& args);
int command_solve_problem(const std::vector<std::string>& args);

}  // namespace deli
