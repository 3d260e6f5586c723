#pragma once

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

#include "simulation/observer.hpp"

namespace deli {

// Aligned thermo table on a stream (the terminal): a header, then a row per sample.
class ThermoTable final : public Observer {
 public:
  explicit ThermoTable(std::FILE* out) : out_(out) {}
  void on_thermo(const ThermoSample& s) override;

 private:
  static bool shown(const std::string& name);
  std::FILE* out_;
  bool header_written_ = false;
};

// The same samples as CSV, one row per sample, flushed at every row so that a run that
// dies keeps everything sampled before.
class ThermoCsv final : public Observer {
 public:
  // continue_from >= 0: a restart at that step appends to the file, cut back to the rows
  // up to it, rows at multiples of `every` (a row at a step that is not, the stopped run's
  // last, is dropped).
  explicit ThermoCsv(const std::string& path, std::int64_t continue_from = -1,
                     std::int64_t every = 0);
  void on_thermo(const ThermoSample& s) override;
  bool wants_shadow_energy() const override { return true; }
  // Closes the file, throwing when it could not be written.
  void on_finish(const System&) override;

 private:
  std::string path_;
  std::ofstream out_;
  std::uintmax_t written_ = 0;  // bytes of whole records in the file
  bool header_written_ = false;
};

// "42% 1234 steps/s ETA 0:12" redrawn in place on a terminal, at most a few times a
// second; erased before other output. Only used when stderr is a terminal.
class ProgressLine final : public Observer {
 public:
  explicit ProgressLine(std::FILE* terminal) : out_(terminal) {}
  void on_start(const System& system, std::int64_t steps) override;
  void on_step(const System& system) override;
  void on_thermo(const ThermoSample&) override { erase(); }
  void on_finish(const System&) override { erase(); }

 private:
  void erase();
  std::FILE* out_;
  std::int64_t first_step_ = 0, steps_ = 0;
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool drawn_ = false;
};

}  // namespace deli
