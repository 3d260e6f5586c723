#include "text/thermo_output.hpp"

#include <cmath>

#include "core/error.hpp"
#include "text/continuation.hpp"
#include "text/write_failure.hpp"

namespace deli {

// The terminal shows the integrator figures a reader checks first; the CSV has them all.
bool ThermoTable::shown(const std::string& name) {
  return name == "min_gap" || name == "max_rod_violation" || name == "reflected" ||
         name == "penetrating_steps";
}

void ThermoTable::on_thermo(const ThermoSample& s) {
  if (!header_written_) {
    std::fprintf(out_, "%10s %12s %14s %14s %14s %12s %12s %10s", "step", "time", "kinetic",
                 "potential", "total", "temperature", "pressure", "|momentum|");
    if (s.conserved) std::fprintf(out_, " %14s", "conserved");
    for (const auto& [name, value] : s.integrator) {
      if (shown(name)) std::fprintf(out_, " %12s", name.c_str());
    }
    std::fprintf(out_, "\n");
    header_written_ = true;
  }
  std::fprintf(out_, "%10lld %12.6g %14.8g %14.8g %14.8g %12.6g %12.6g %10.3g",
               static_cast<long long>(s.step), s.time, s.kinetic, s.potential, s.total,
               s.temperature, s.pressure, norm(s.momentum));
  if (s.conserved) std::fprintf(out_, " %14.8g", *s.conserved);
  for (const auto& [name, value] : s.integrator) {
    if (shown(name)) std::fprintf(out_, " %12.4g", value);
  }
  std::fprintf(out_, "\n");
  // A full disk behind a redirected stdout: stop rather than run on without a log.
  if (std::fflush(out_) != 0 || std::ferror(out_)) {
    throw SimulationError("could not write the thermo table to standard output at step " +
                          std::to_string(s.step) + " (disk full?)");
  }
}

ThermoCsv::ThermoCsv(const std::string& path, std::int64_t continue_from, std::int64_t every)
    : path_(path) {
  if (continue_from >= 0) {
    // A row at the checkpoint's step is the stopped run's own last row unless the step is a
    // regular one (the start, a multiple of `every`): the uninterrupted run has no such row.
    const bool regular = continue_from == 0 || (every > 0 && continue_from % every == 0);
    header_written_ = cut_back_after_step(
        path, regular ? continue_from : continue_from - 1,
        [](const std::vector<std::string>& lines, std::size_t k) -> std::optional<std::int64_t> {
          if (k == 0 || lines[k].empty()) return std::nullopt;  // the header
          return std::stoll(lines[k].substr(0, lines[k].find(',')));
        });
  }
  out_.open(path, header_written_ ? std::ios::app : std::ios::trunc);
  if (!out_)
    throw InputError(path +
                     ": cannot open the thermo file for writing; check the "
                     "directory exists and is writable");
  written_ = bytes_in_file(path);
  out_.precision(17);
}

void ThermoCsv::on_thermo(const ThermoSample& s) {
  if (!header_written_) {
    out_ << "step,time,kinetic,potential,total,temperature,pressure,px,py,pz";
    for (const std::string& name : s.term_names) out_ << ",e_" << name;
    if (s.shadow_energy) out_ << ",shadow_energy";
    if (s.conserved) out_ << ",bath_energy,conserved";
    if (s.angular_momentum) out_ << ",Lx,Ly,Lz";
    for (const auto& [name, value] : s.integrator) out_ << ',' << name;
    out_ << '\n';
    header_written_ = true;
  }
  out_ << s.step << ',' << s.time << ',' << s.kinetic << ',' << s.potential << ',' << s.total << ','
       << s.temperature << ',' << s.pressure << ',' << s.momentum.x << ',' << s.momentum.y << ','
       << s.momentum.z;
  for (double e : s.term_energies) out_ << ',' << e;
  if (s.shadow_energy) out_ << ',' << *s.shadow_energy;
  if (s.conserved) out_ << ',' << *s.bath_energy << ',' << *s.conserved;
  if (s.angular_momentum) {
    out_ << ',' << s.angular_momentum->x << ',' << s.angular_momentum->y << ','
         << s.angular_momentum->z;
  }
  for (const auto& [name, value] : s.integrator) out_ << ',' << value;
  out_ << '\n';
  out_.flush();
  if (!out_) {
    drop_partial_record(out_, path_, written_);
    throw SimulationError(path_ + ": could not write the thermo row of step " +
                          std::to_string(s.step) +
                          " (disk full or not writable?); the rows before it are kept");
  }
  written_ = bytes_in_file(path_);
}

void ThermoCsv::on_finish(const System&) {
  if (!out_.is_open()) return;
  out_.close();
  if (!out_) {
    throw SimulationError(path_ + ": could not close the thermo file (disk full?)");
  }
}

void ProgressLine::on_start(const System& system, std::int64_t steps) {
  first_step_ = system.step;
  steps_ = steps;
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

void ProgressLine::on_step(const System& system) {
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(250)) return;
  last_draw_ = now;
  const double done = static_cast<double>(system.step - first_step_);
  const double seconds = std::chrono::duration<double>(now - start_).count();
  const double rate = seconds > 0 ? done / seconds : 0.0;
  const double eta = rate > 0 ? (static_cast<double>(steps_) - done) / rate : 0.0;
  const long eta_s = std::lround(eta);
  std::fprintf(out_, "\r\033[K%5.1f%%  %.4g steps/s  ETA %ld:%02ld:%02ld",
               100.0 * done / static_cast<double>(steps_), rate, eta_s / 3600, (eta_s / 60) % 60,
               eta_s % 60);
  std::fflush(out_);
  drawn_ = true;
}

void ProgressLine::erase() {
  if (!drawn_) return;
  std::fprintf(out_, "\r\033[K");
  std::fflush(out_);
  drawn_ = false;
}

}  // namespace deli
