#include <cstdio>

#include "cli/commands.hpp"
#include "cli/exit_status.hpp"
#include "core/error.hpp"
#include "crosscheck/validate.hpp"
#include "simulation/thermo.hpp"

namespace deli {

namespace {

ValidateOptions parse_options(const std::vector<std::string>& args, std::string& input) {
  ValidateOptions options;
  for (std::size_t k = 0; k < args.size(); ++k) {
    const std::string& a = args[k];
    auto value = [&]() -> std::string {
      if (k + 1 >= args.size()) throw InputError("deli validate: " + a + " needs a value");
      return args[++k];
    };
    if (a == "--engine") {
      const std::string e = value();
      if (e != "openmm" && e != "lammps" && e != "all") {
        throw InputError("deli validate: --engine " + e + ": expected openmm, lammps or all");
      }
      options.openmm = e != "lammps";
      options.lammps = e != "openmm";
    } else if (a == "--platform") {
      const std::string p = value();
      if (p != "reference" && p != "cpu") {
        throw InputError("deli validate: --platform " + p + ": expected reference or cpu");
      }
      options.openmm_cpu = p == "cpu";
    } else if (a == "--steps") {
      const std::string s = value();
      try {
        options.trajectory_steps = std::stoi(s);
      } catch (const std::exception&) {
        throw InputError("deli validate: --steps " + s + ": expected a number of steps");
      }
      if (options.trajectory_steps < 0) throw InputError("deli validate: --steps must be >= 0");
    } else if (!a.empty() && a[0] == '-') {
      throw InputError("deli validate: unknown option " + a + "; see deli --help");
    } else if (input.empty()) {
      input = a;
    } else {
      throw InputError("deli validate takes one INPUT; see deli --help");
    }
  }
  if (input.empty())
    throw InputError(
        "usage: deli validate INPUT [--engine openmm|lammps|all] "
        "[--platform reference|cpu] [--steps N]");
  return options;
}

std::string engine_value(const ValidationReport& r, const std::string& engine,
                         const std::string& quantity) {
  for (const Check& c : r.checks) {
    if (c.engine == engine && c.quantity == quantity) {
      char buffer[64];
      std::snprintf(buffer, sizeof buffer, "%.15g", c.other_value);
      return buffer;
    }
  }
  return "-";
}

}  // namespace

int command_validate(const std::vector<std::string>& args) {
  std::string path;
  const ValidateOptions options = parse_options(args, path);
  const RunInput input = load_run_input(path);
  const System& s = input.system;
  std::printf("deli validate %s: %zu atoms, %zu bonds, %zu angles, boundary %c%c%c\n", path.c_str(),
              s.particles.size(), s.topology.bonds.size(), s.topology.angles.size(),
              s.box.periodic(0) ? 'p' : 'f', s.box.periodic(1) ? 'p' : 'f',
              s.box.periodic(2) ? 'p' : 'f');
  ValidateOptions with_progress = options;
  with_progress.progress = [](const std::string& line) {
    std::fprintf(stderr, "deli validate: %s\n", line.c_str());
    std::fflush(stderr);
  };
  ValidationReport report;
  try {
    report = validate(input, with_progress);
  } catch (const UnsupportedModel& e) {
    throw InputError(path + ": " + e.what());
  }
  for (const std::string& note : report.notes) std::printf("note: %s\n", note.c_str());
  for (const SkippedCheck& skip : report.skipped) {
    std::printf("skipped: %s %s (%s): %s\n",
                skip.engine == "all" ? "every engine's" : skip.engine.c_str(), skip.check.c_str(),
                skip_reason_name(skip.reason), skip.why.c_str());
  }

  // Energies side by side, then every check with its difference and tolerance.
  std::printf("\n%-14s %24s", "energy", "deli");
  for (const EngineEvaluation& e : report.others) std::printf(" %24s", e.engine.c_str());
  std::printf("\n");
  auto row = [&](const std::string& label, double deli_value, const std::string& quantity) {
    std::printf("%-14s %24.15g", label.c_str(), deli_value);
    for (const EngineEvaluation& e : report.others) {
      std::printf(" %24s", engine_value(report, e.engine, quantity).c_str());
    }
    std::printf("\n");
  };
  for (std::size_t t = 0; t < report.deli.term_names.size(); ++t) {
    row(report.deli.term_names[t], report.deli.term_energies[t],
        "energy " + report.deli.term_names[t]);
  }
  row("total", report.deli.potential, "energy total");
  if (report.deli.virial) {
    row("virial W", *report.deli.virial, "virial W");
    // Pressure (2K + W) / 3V from each engine's virial, with deli's kinetic energy and box.
    const double two_k = 2.0 * kinetic_energy(s.particles), volume3 = 3.0 * s.box.volume();
    std::printf("%-14s %24.15g", "pressure", (two_k + *report.deli.virial) / volume3);
    for (const EngineEvaluation& e : report.others) {
      if (e.virial) {
        std::printf(" %24.15g", (two_k + *e.virial) / volume3);
      } else {
        std::printf(" %24s", "-");
      }
    }
    std::printf("\n");
  }

  std::printf("\n%-18s %-34s %12s %10s  %-6s %s\n", "engine", "check", "difference", "tolerance",
              "", "where");
  for (const Check& c : report.checks) {
    std::printf("%-18s %-34s %12.3e %10.1e  %-6s %s\n", c.engine.c_str(), c.quantity.c_str(),
                c.difference, c.tolerance, c.within() ? "ok" : "FAIL", c.where.c_str());
  }
  const Check* worst = report.worst();
  if (report.passed()) {
    std::printf("\nagreement: every check within tolerance");
    if (worst)
      std::printf(" (closest: %s %s at %.2g of its tolerance)", worst->engine.c_str(),
                  worst->quantity.c_str(), worst->difference / worst->tolerance);
    std::printf("\n");
    return 0;
  }
  std::fprintf(stderr, "deli validate: disagreement: %s %s differs by %.3e (tolerance %.1e)%s%s\n",
               worst->engine.c_str(), worst->quantity.c_str(), worst->difference, worst->tolerance,
               worst->where.empty() ? "" : " at ", worst->where.c_str());
  return kExitDisagreement;
}

}  // namespace deli
