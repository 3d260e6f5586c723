#include "crosscheck/lammps_bridge.hpp"

#include <library.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <unordered_map>

#include "crosscheck/single_process_mpi.hpp"
#include "input/lammps_data.hpp"

namespace deli {

namespace {
std::string number(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}
}  // namespace

LammpsBridge::LammpsBridge(const System& system, const ForceFieldSpec& spec, double skin) {
  if (spec.pair && spec.pair->style->lammps_style.empty()) {
    throw UnsupportedModel("LAMMPS has no pair style '" + spec.pair->style->name + "'");
  }
  const std::array<std::pair<const char*, const std::optional<BondedSpec>*>, 3> kinds{
      {{"bond", &spec.bond}, {"angle", &spec.angle}, {"dihedral", &spec.dihedral}}};
  for (const auto& [kind, bonded] : kinds) {
    if (!*bonded) continue;
    for (const BondedStyle* style : (*bonded)->styles()) {
      if (style->lammps_style.empty()) {
        throw UnsupportedModel("LAMMPS has no " + std::string(kind) + " style '" + style->name +
                               "'");
      }
    }
  }
  const bool bonds = !system.topology.bonds.empty(), angles = !system.topology.angles.empty(),
             dihedrals = !system.topology.dihedrals.empty();
  // Terms as deli has them: bonds held as rods are in the topology but not in the force field.
  has_bonds_ = bonds && spec.bond;
  has_angles_ = angles && spec.angle;
  has_dihedrals_ = dihedrals && spec.dihedral;
  has_pair_ = spec.pair.has_value();
  const std::string style = dihedrals ? "molecular" : angles ? "angle" : bonds ? "bond" : "atomic";
  data_path_ = (std::filesystem::temp_directory_path() /
                ("deli-validate-" + std::to_string(getpid()) + ".data"))
                   .string();
  // read_data drops atoms outside the box even along shrink-wrapped axes (a LAMMPS error,
  // which ends the process): open axes get bounds around every atom, at least the
  // neighbour cutoff away, and are shrink-wrapped no closer (boundary m): a box flat
  // along an open axis (one atom, a planar pendulum) would else be thinner than a
  // neighbour bin, another LAMMPS error.
  System copy = system;
  Vec3 lo = system.box.lo(), hi = system.box.hi();
  const double pad = std::max(1.0, (spec.pair ? spec.pair->max_cutoff() : 1.0) + skin);
  for (const Vec3& x : system.particles.position) {
    for (int a = 0; a < 3; ++a) {
      if (system.box.periodic(a)) continue;
      lo[a] = std::min(lo[a], x[a] - pad);
      hi[a] = std::max(hi[a], x[a] + pad);
    }
  }
  copy.box = Box(lo, hi, system.box.periodic());
  write_lammps_data(copy, data_path_, style, "deli validate");
  ids_ = system.particles.id;

  const char* args[] = {"deli", "-screen", "none", "-log", "none", "-nocite"};
  prefer_single_process_mpi();
  lammps_ = lammps_open_no_mpi(6, const_cast<char**>(args), nullptr);
  // A missing style would be a LAMMPS error, which ends the process: ask first.
  const bool external = spec.gravity || !spec.radial.empty();
  auto unsupported = [&](const std::string& what) {
    lammps_close(lammps_);
    lammps_ = nullptr;
    std::error_code ignored;
    std::filesystem::remove(data_path_, ignored);
    throw UnsupportedModel("this LAMMPS has no " + what);
  };
  for (const char* fix : {"gravity", "addforce"}) {
    if (external && !lammps_has_style(lammps_, "fix", fix)) {
      unsupported(std::string("fix ") + fix + " (needed for the input's external field)");
    }
  }
  if (spec.pair && !lammps_has_style(lammps_, "pair", spec.pair->style->lammps_style.c_str())) {
    unsupported("pair_style " + spec.pair->style->lammps_style);
  }
  for (const auto& [kind, bonded] : kinds) {
    if (!*bonded) continue;
    std::vector<std::string> needed;
    for (const BondedStyle* style : (*bonded)->styles()) needed.push_back(style->lammps_style);
    if (needed.size() > 1) needed.push_back("hybrid");
    for (const std::string& name : needed) {
      if (!lammps_has_style(lammps_, kind, name.c_str())) {
        unsupported(std::string(kind) + "_style " + name);
      }
    }
  }

  std::string boundary;
  for (int a = 0; a < 3; ++a) boundary += system.box.periodic(a) ? "p " : "m ";
  command("units lj");
  command("atom_style " + style);
  command("atom_modify map array");
  command("boundary " + boundary);
  command("read_data " + data_path_);
  command("neighbor " + number(skin) + " bin");
  command("neigh_modify delay 0 every 1 check yes");
  command("special_bonds lj " + number(spec.special_lj[0]) + " " + number(spec.special_lj[1]) +
          " " + number(spec.special_lj[2]));
  if (spec.pair) {
    const PairCoefficients& c = spec.pair->coefficients;
    command("pair_style " + spec.pair->style->lammps_style + " " + number(spec.pair->max_cutoff()));
    for (int a = 0; a < c.type_count(); ++a) {
      for (int b = a; b < c.type_count(); ++b) {
        const PairCoefficient& p = c.at(a, b);
        std::string line = "pair_coeff " + std::to_string(a + 1) + " " + std::to_string(b + 1);
        for (double v : p.values) line += " " + number(v);
        command(line + " " + number(p.cutoff));
      }
    }
    command(std::string("pair_modify shift ") + (spec.pair->shift ? "yes" : "no"));
  } else {
    command("pair_style zero 1.0");
    command("pair_coeff * *");
  }
  if (spec.bond) bonded_style("bond", *spec.bond);
  if (bonds && !spec.bond) {  // rods: bonds for the exclusions, no force
    command("bond_style zero");
    command("bond_coeff *");
  }
  if (angles && !spec.angle) {
    command("angle_style zero");
    command("angle_coeff *");
  }
  if (spec.dihedral) bonded_style("dihedral", *spec.dihedral);
  // External fields: fix gravity (F = m g, energy -m g.x) and, for each radial field, fix
  // addforce with atom-style variables for the force and the energy (deli's V(s) with
  // s = |x - c|^2: F = -2 V'(s) (x - c)). Both count in pe (fix_modify energy yes) and,
  // as deli's, not in the virial (fix_modify virial is off by default).
  if (spec.gravity) {
    const Vec3 g = *spec.gravity;
    const double magnitude = norm(g);
    if (magnitude > 0) {
      command("fix deli_gravity all gravity " + number(magnitude) + " vector " + number(g.x) + " " +
              number(g.y) + " " + number(g.z));
      command("fix_modify deli_gravity energy yes");
      external_fixes_.push_back("deli_gravity");
    }
  }
  for (std::size_t r = 0; r < spec.radial.size(); ++r) {
    const ForceFieldSpec::Radial& radial = spec.radial[r];
    const std::string tag = "deli_r" + std::to_string(r) + "_";
    auto par = [](double v) { return "(" + number(v) + ")"; };
    const std::string dx = "(x-" + par(radial.center.x) + ")",
                      dy = "(y-" + par(radial.center.y) + ")",
                      dz = "(z-" + par(radial.center.z) + ")";
    command("variable " + tag + "s atom " + dx + "^2+" + dy + "^2+" + dz + "^2");
    const std::string s = "v_" + tag + "s";
    std::string energy, slope;  // V(s) and V'(s)
    if (radial.inverse_square) {
      energy = par(radial.coefficients[0]) + "/" + s;
      slope = "-" + par(radial.coefficients[0]) + "/(" + s + "^2)";
    } else {
      const std::vector<double>& a = radial.coefficients;
      for (std::size_t k = a.size(); k-- > 0;) {
        energy = energy.empty() ? par(a[k]) : par(a[k]) + "+" + s + "*(" + energy + ")";
        if (k >= 1) {
          const std::string term = par(static_cast<double>(k) * a[k]);
          slope = slope.empty() ? term : term + "+" + s + "*(" + slope + ")";
        }
      }
      if (energy.empty()) energy = "0";
      if (slope.empty()) slope = "0";
    }
    command("variable " + tag + "e atom " + energy);
    command("variable " + tag + "d atom " + slope);
    for (const char* axis : {"x", "y", "z"}) {
      const std::string d = axis[0] == 'x' ? dx : axis[0] == 'y' ? dy : dz;
      command("variable " + tag + "f" + axis + " atom -2*v_" + tag + "d*" + d);
    }
    command("fix " + tag + "fix all addforce v_" + tag + "fx v_" + tag + "fy v_" + tag +
            "fz energy v_" + tag + "e");
    command("fix_modify " + tag + "fix energy yes");
    external_fixes_.push_back(tag + "fix");
  }
  if (spec.angle) bonded_style("angle", *spec.angle);
  command("compute deli_virial all pressure NULL virial");
  command("compute deli_unwrapped all property/atom xu yu zu");
  command("thermo_style custom step pe ke evdwl ebond eangle edihed press vol c_deli_virial");
  command("thermo_modify norm no");
}

// "<kind>_style" and one "<kind>_coeff" line per type: the registered style's name and its
// coefficients in order, angles back in degrees; several styles as LAMMPS' hybrid, each
// coeff line naming its type's style.
void LammpsBridge::bonded_style(const std::string& kind, const BondedSpec& bonded) {
  const std::vector<const BondedStyle*> styles = bonded.styles();
  const bool hybrid = styles.size() > 1;
  std::string line = kind + "_style" + (hybrid ? " hybrid" : "");
  for (const BondedStyle* style : styles) line += " " + style->lammps_style;
  command(line);
  for (std::size_t t = 0; t < bonded.by_type.size(); ++t) {
    const BondedStyle& style = *bonded.style_by_type[t];
    line = kind + "_coeff " + std::to_string(t + 1) + (hybrid ? " " + style.lammps_style : "");
    for (std::size_t k = 0; k < bonded.by_type[t].size(); ++k) {
      const double v = bonded.by_type[t][k];
      line += " " + number(style.coefficients[k].degrees ? v * 180.0 / std::numbers::pi : v);
    }
    command(line);
  }
}

LammpsBridge::~LammpsBridge() {
  if (lammps_) lammps_close(lammps_);
  std::error_code ignored;
  std::filesystem::remove(data_path_, ignored);
}

void LammpsBridge::command(const std::string& line) {
  lammps_command(lammps_, line.c_str());
}

// A per-atom vector quantity, reordered from LAMMPS' local order to deli's indices.
std::vector<Vec3> LammpsBridge::per_atom(const char* name, bool is_compute) {
  const int n = lammps_extract_setting(lammps_, "nlocal");
  const auto* tag = static_cast<const int*>(lammps_extract_atom(lammps_, "id"));
  double** values = is_compute ? static_cast<double**>(lammps_extract_compute(
                                     lammps_, name, LMP_STYLE_ATOM, LMP_TYPE_ARRAY))
                               : static_cast<double**>(lammps_extract_atom(lammps_, name));
  std::unordered_map<std::int64_t, Vec3> by_id;
  for (int k = 0; k < n; ++k) by_id[tag[k]] = {values[k][0], values[k][1], values[k][2]};
  std::vector<Vec3> out;
  out.reserve(ids_.size());
  for (std::int64_t id : ids_) out.push_back(by_id.at(id));
  return out;
}

EngineEvaluation LammpsBridge::evaluate() {
  command("run 0");
  EngineEvaluation e;
  e.engine = name();
  if (has_pair_) {
    e.term_names.push_back("pair");
    e.term_energies.push_back(lammps_get_thermo(lammps_, "evdwl"));
  }
  if (has_bonds_) {
    e.term_names.push_back("bond");
    e.term_energies.push_back(lammps_get_thermo(lammps_, "ebond"));
  }
  if (has_angles_) {
    e.term_names.push_back("angle");
    e.term_energies.push_back(lammps_get_thermo(lammps_, "eangle"));
  }
  if (has_dihedrals_) {
    e.term_names.push_back("dihedral");
    e.term_energies.push_back(lammps_get_thermo(lammps_, "edihed"));
  }
  if (!external_fixes_.empty()) {
    double external = 0.0;
    for (const std::string& fix : external_fixes_) {
      auto* value = static_cast<double*>(
          lammps_extract_fix(lammps_, fix.c_str(), LMP_STYLE_GLOBAL, LMP_TYPE_SCALAR, 0, 0));
      external += *value;
      lammps_free(value);
    }
    e.term_names.push_back("external");
    e.term_energies.push_back(external);
  }
  e.potential = lammps_get_thermo(lammps_, "pe");
  // The virial pressure is W / (3 V) in LAMMPS' own (shrink-wrapped, if open) volume.
  const double* virial_pressure = static_cast<const double*>(
      lammps_extract_compute(lammps_, "deli_virial", LMP_STYLE_GLOBAL, LMP_TYPE_SCALAR));
  e.virial = *virial_pressure * 3.0 * lammps_get_thermo(lammps_, "vol");
  e.force = per_atom("f", false);
  return e;
}

std::vector<Vec3> LammpsBridge::run_nve(int steps, double dt) {
  command("timestep " + number(dt));
  command("fix deli_nve all nve");
  command("run " + std::to_string(steps));
  command("unfix deli_nve");
  return per_atom("deli_unwrapped", true);
}

EnergySeries LammpsBridge::run_langevin(const LangevinRun& run) {
  command("timestep " + number(run.timestep));
  command("fix deli_nve all nve");
  // zero no (the default): the random forces are not made to sum to zero, so that every
  // one of the 3N degrees of freedom, the centre of mass included, is thermalised as in
  // OpenMM's and deli's Langevin (with zero yes the drag alone acts on the centre of mass,
  // which then comes to rest: 3 degrees of freedom fewer).
  command("fix deli_langevin all langevin " + number(run.temperature) + " " +
          number(run.temperature) + " " + number(run.damping) + " " + std::to_string(run.seed) +
          " zero no");
  command("run " + std::to_string(run.equilibration));
  EnergySeries series;
  for (int s = 0; s < run.samples; ++s) {
    // The thermo keywords are evaluated at the last step of every run.
    command("run " + std::to_string(run.every) + " pre no post no");
    series.potential.push_back(lammps_get_thermo(lammps_, "pe"));
    series.kinetic.push_back(lammps_get_thermo(lammps_, "ke"));
  }
  command("unfix deli_langevin");
  command("unfix deli_nve");
  return series;
}

}  // namespace deli
