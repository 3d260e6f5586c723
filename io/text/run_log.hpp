#pragma once

#include <cstdio>
#include <string>

namespace deli {

// What `deli run` prints: on the terminal (stdout) and, with [output] log = "FILE", the
// same lines in that file (as LAMMPS' log.lammps). A restart appends to the log.
class RunLog {
 public:
  RunLog() = default;
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;
  ~RunLog();

  // Throws InputError when the file cannot be opened.
  void open(const std::string& path, bool append);
  // printf to both; a failed write to the log stops the run (SimulationError).
  [[gnu::format(printf, 2, 3)]] void print(const char* format, ...);
  // The log's stream for observers that write themselves (the thermo table); nullptr if none.
  std::FILE* file() const { return file_; }
  // Closes the log, throwing if what was written could not be flushed.
  void close();

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
};

}  // namespace deli
