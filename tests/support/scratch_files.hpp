#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace deli::testing {

// Files one test writes to the temporary folder, removed with it. Names carry the test's
// name and the process id, because ctest runs tests in parallel.
class ScratchFiles {
 public:
  ScratchFiles(std::string prefix, std::string extension)
      : prefix_(std::move(prefix)), extension_(std::move(extension)) {}
  ScratchFiles(const ScratchFiles&) = delete;
  ScratchFiles& operator=(const ScratchFiles&) = delete;
  ~ScratchFiles() {
    for (const std::string& path : paths_) std::filesystem::remove(path);
  }

  // A new file holding `contents`; its path.
  std::string write(const std::string& contents) {
    const std::string name =
        prefix_ + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
        std::to_string(::getpid()) + "_" + std::to_string(paths_.size()) + extension_;
    paths_.push_back((std::filesystem::temp_directory_path() / name).string());
    std::ofstream(paths_.back(), std::ios::binary) << contents;
    return paths_.back();
  }

 private:
  std::string prefix_, extension_;
  std::vector<std::string> paths_;
};

// The working directory, for one test, moved to a new directory of its own under the
// temporary folder (named from `name` and the process id), and back when it ends, the
// directory removed. For code that writes to the working directory under fixed names (a
// failed solve's problem file), which other tests running at the same time also write.
class ScratchDirectory {
 public:
  explicit ScratchDirectory(const std::string& name)
      : home_(std::filesystem::current_path()),
        own_(std::filesystem::temp_directory_path() /
             ("deli-" + name + "-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(own_);
    std::filesystem::current_path(own_);
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;
  ~ScratchDirectory() {
    std::filesystem::current_path(home_);
    std::filesystem::remove_all(own_);
  }
  const std::filesystem::path& path() const { return own_; }

 private:
  std::filesystem::path home_, own_;
};

}  // namespace deli::testing
