#include "text/run_log.hpp"

#include <cerrno>
#include <cstdarg>
#include <cstring>

#include "core/error.hpp"

namespace deli {

RunLog::~RunLog() {
  if (file_) std::fclose(file_);
}

void RunLog::open(const std::string& path, bool append) {
  file_ = std::fopen(path.c_str(), append ? "a" : "w");
  if (!file_) {
    throw InputError(path + ": cannot open the log for writing (" + std::strerror(errno) +
                     "); check the directory exists and is writable");
  }
  path_ = path;
}

void RunLog::print(const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  std::va_list copy;
  va_copy(copy, args);
  std::vfprintf(stdout, format, args);
  va_end(args);
  if (file_) {
    const int written = std::vfprintf(file_, format, copy);
    if (written < 0 || std::fflush(file_) != 0) {
      va_end(copy);
      throw SimulationError(path_ + ": could not write the log (" + std::strerror(errno) +
                            "; disk full?)");
    }
  }
  va_end(copy);
}

void RunLog::close() {
  if (!file_) return;
  std::FILE* f = file_;
  file_ = nullptr;
  const bool failed = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || failed) {
    throw SimulationError(path_ + ": could not complete the log (disk full?)");
  }
}

}  // namespace deli
