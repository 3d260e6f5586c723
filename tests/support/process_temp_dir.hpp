#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace deli::testing {

// This test process's own folder under the temporary folder, made on first use and removed
// when the process ends. Tests write inputs and outputs there under fixed names
// ("short.toml"), which two suites running at once (a developer's and CI's, or the
// sanitizer build's beside the plain one) would otherwise share in /tmp itself; ctest runs
// each test in its own process, so the process id makes the folder the test's alone.
inline const std::string& process_temp_dir() {
  struct Folder {
    pid_t owner = ::getpid();
    std::filesystem::path path =
        std::filesystem::path(::testing::TempDir()) / ("deli-test-" + std::to_string(owner));
    Folder() {
      std::filesystem::remove_all(path);  // left by a killed process of the same id
      std::filesystem::create_directories(path);
    }
    // A forked child (a death test) exits through here too: the folder is its parent's.
    ~Folder() {
      if (::getpid() != owner) return;
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  static const std::string name = folder.path.string();
  return name;
}

}  // namespace deli::testing
