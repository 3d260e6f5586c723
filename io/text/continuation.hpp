#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace deli {

// The step at which a record (a CSV row, a dump frame) starting at lines[k] begins, or
// nothing where no record starts.
using RecordStep = std::function<std::optional<std::int64_t>(const std::vector<std::string>& lines,
                                                             std::size_t k)>;

// A run restarted from a checkpoint at `step` appends to its text outputs: this cuts the file
// back to the records at or before `step` (the run that wrote the checkpoint had written
// those; the restarted run writes the later ones again). A last line cut short is dropped.
// Returns whether the file existed and kept anything.
bool cut_back_after_step(const std::string& path, std::int64_t step, const RecordStep& record_step);

}  // namespace deli
