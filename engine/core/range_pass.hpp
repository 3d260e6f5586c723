#pragma once

#include <cstddef>
#include <functional>

namespace deli {

// A caller's pass over the items [begin, end) (particles), handed to a loop that runs it on
// each of its chunks, in its own job: a job of the team fewer than a pass of its own.
using RangePass = std::function<void(std::size_t begin, std::size_t end)>;

}  // namespace deli
