#pragma once

#include <string>
#include <vector>

namespace deli {

struct RunInput;

// The input's [run] settings of how the loops are cut into chunks (balance_threads,
// split_small_loops), for this process, as `deli run` applies them.
void apply_chunk_settings(const RunInput& input);

// Each returns the process exit status; errors are thrown (InputError, SimulationError).
int command_run(const std::vector<std::string>& args);
int command_write_data(const std::vector<std::string>& args);
int command_validate(const std::vector<std::string>& args);
int command_info(const std::vector<std::string>& args);
int command_solve_problem(const std::vector<std::string>& args);

}  // namespace deli
