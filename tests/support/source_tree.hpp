#pragma once

#include <string>

namespace deli::testing {

// The source tree's root, where the tests find the shipped inputs (DELI_SOURCE_DIR is set
// by tests/CMakeLists.txt). One definition for every test file: the test files of a binary
// are compiled together in batches (DELI_UNITY_TESTS).
inline const std::string kSource = DELI_SOURCE_DIR;

}  // namespace deli::testing
