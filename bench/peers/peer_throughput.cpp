// deli-peers: the throughput of OpenMM (C++ API, CPU platform) and LAMMPS (liblammps, in this
// process) on a deli input's model, for bench/constrained.sh and bench/threads.sh. Not a test.
//
//   deli-peers INPUT.toml STEPS openmm [TOLERANCE [THREADS]]
//       Verlet; the input's rods as constraints (CCMA) held to TOLERANCE (default 1e-4);
//       the CPU platform on THREADS threads (default 1)
//   deli-peers INPUT.toml STEPS lammps [K]
//       fix nve; with rods, fix rattle on the rods LAMMPS can hold (below), the others
//       harmonic bonds of stiffness K (100). Started by mpirun -np R, LAMMPS runs on R ranks
//       (liblammps initialises MPI itself) and rank 0 alone reports.
//
// Prints one line: "atom-steps/s X" and what ran. The clock covers the integration loop only
// (after a few warm-up steps in OpenMM, LAMMPS' run setup included), as deli's "loop time".
//
// The same model as deli: lj/cut with one atom type, shifted (the shift changes energies, not
// forces), special_bonds lj 0 1 1 as exclusions, harmonic bonds (E = K (r - r0)^2, OpenMM's
// k = 2 K) or rods. OpenMM gets its fastest path for this model, NonbondedForce with zero
// charges (cutoff, no switching, no dispersion correction), not the CustomNonbondedForce the
// cross-check bridge uses for any pair style. LAMMPS' fix shake and fix rattle hold clusters
// of at most 4 atoms bonded to one central atom: a chain of rods is no such cluster. With rods,
// LAMMPS gets a different model, every chain cut into rigid three-bead pieces joined by
// harmonic bonds (2/3 of the bonds rigid), reported as such.
#include <OpenMM.h>
#include <library.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "crosscheck/single_process_mpi.hpp"
#include "input/lammps_data.hpp"
#include "input/run_input.hpp"
#include "integrators/gvi.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string number(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

struct Model {
  deli::System start;  // on the rods, velocities tangent (as deli run starts)
  std::vector<deli::Constraint> rods;
  double epsilon = 1, sigma = 1, cutoff = 2.5;
  std::vector<double> bond_k, bond_r0;  // by bond type (empty with rods only)
  double timestep = 0.005, skin = 0.3;
};

// The input's model, checked to be the one this driver translates.
Model load_model(const std::string& path) {
  deli::RunInput input = deli::load_run_input(path);
  const deli::ForceFieldSpec& spec = input.force_field_spec;
  auto refuse = [&](const std::string& why) {
    throw std::runtime_error(path +
                             ": deli-peers translates one-type lj/cut with harmonic bonds "
                             "or rods, special_bonds lj 0 1 1, periodic box; " +
                             why);
  };
  if (!spec.pair || spec.pair->style->name != "lj/cut" || spec.pair->coefficients.type_count() != 1)
    refuse("the pair style is not lj/cut with one atom type");
  // Without bonds (a simple liquid) the special_bonds factors apply to no pair.
  if (!input.system.topology.bonds.empty() &&
      spec.special_lj != std::array<double, 3>{0.0, 1.0, 1.0})
    refuse("special_bonds differ");
  if (spec.angle || spec.gravity || !spec.radial.empty()) refuse("it has angles or fields");
  for (bool p : input.system.box.periodic()) {
    if (!p) refuse("an axis is open");
  }
  const deli::ConstraintSet& constraints = input.constraints;
  if (!constraints.walls.empty() || constraints.hard_spheres) refuse("it has hard contacts");
  Model m;
  for (const deli::Constraint& row : constraints.equalities) {
    if (row.kind != deli::ConstraintKind::rod) refuse("it has constraints other than rods");
    m.rods.push_back(row);
  }
  if (spec.bond) {
    for (std::size_t t = 0; t < spec.bond->by_type.size(); ++t) {
      if (spec.bond->style_by_type[t]->name != "harmonic") refuse("a bond style is not harmonic");
      m.bond_k.push_back(spec.bond->by_type[t][0]);
      m.bond_r0.push_back(spec.bond->by_type[t][1]);
    }
  }
  const deli::PairCoefficient& lj = spec.pair->coefficients.at(0, 0);
  m.epsilon = lj.values[0];
  m.sigma = lj.values[1];
  m.cutoff = lj.cutoff;
  m.timestep = input.timestep;
  m.skin = input.skin;
  m.start = input.system;
  if (!m.rods.empty()) {
    deli::GviOptions options = input.gvi;
    options.timestep = input.timestep;
    options.skin = input.skin;
    deli::Gvi gvi(*input.force_field, constraints, options, m.start.particles);
    gvi.setup(m.start);
  }
  if (input.start_temperature) {
    deli::set_temperature(m.start.particles, input.degrees_of_freedom, *input.start_temperature);
  }
  return m;
}

void report(const char* engine, std::size_t atoms, int steps, double seconds,
            const std::string& what) {
  std::printf("atom-steps/s %.4g  %s: %d steps of %zu atoms in %.3f s; %s\n",
              static_cast<double>(atoms) * steps / seconds, engine, steps, atoms, seconds,
              what.c_str());
}

void run_openmm(const Model& m, int steps, double tolerance, int threads) {
  const deli::System& s = m.start;
  const std::size_t n = s.particles.size();
  OpenMM::System system;
  const deli::Vec3 length = s.box.length();
  system.setDefaultPeriodicBoxVectors(OpenMM::Vec3(length.x, 0, 0), OpenMM::Vec3(0, length.y, 0),
                                      OpenMM::Vec3(0, 0, length.z));
  for (double mass : s.particles.mass) system.addParticle(mass);
  auto* pair = new OpenMM::NonbondedForce();
  pair->setNonbondedMethod(OpenMM::NonbondedForce::CutoffPeriodic);
  pair->setCutoffDistance(m.cutoff);
  pair->setUseSwitchingFunction(false);
  pair->setUseDispersionCorrection(false);
  for (std::size_t i = 0; i < n; ++i) pair->addParticle(0.0, m.sigma, m.epsilon);
  for (const deli::Bond& b : s.topology.bonds) pair->addException(b.i, b.j, 0.0, m.sigma, 0.0);
  system.addForce(pair);
  if (!m.bond_k.empty()) {
    auto* bonds = new OpenMM::HarmonicBondForce();
    for (const deli::Bond& b : s.topology.bonds) {
      bonds->addBond(b.i, b.j, m.bond_r0[b.type], 2.0 * m.bond_k[b.type]);
    }
    bonds->setUsesPeriodicBoundaryConditions(true);
    system.addForce(bonds);
  }
  for (const deli::Constraint& rod : m.rods) system.addConstraint(rod.i, rod.j, rod.length);

  OpenMM::Platform::loadPluginsFromDirectory(OpenMM::Platform::getDefaultPluginsDirectory());
  OpenMM::Platform::loadPluginsFromDirectory(DELI_OPENMM_PLUGIN_DIR);
  OpenMM::VerletIntegrator verlet(m.timestep);
  verlet.setConstraintTolerance(tolerance);
  OpenMM::Context context(system, verlet, OpenMM::Platform::getPlatformByName("CPU"),
                          {{"Threads", std::to_string(threads)}});
  std::vector<OpenMM::Vec3> x, v;
  for (std::size_t i = 0; i < n; ++i) {
    const deli::Vec3 u = s.box.unwrapped(s.particles.position[i], s.particles.image[i]);
    x.emplace_back(u.x, u.y, u.z);
    const deli::Vec3& w = s.particles.velocity[i];
    v.emplace_back(w.x, w.y, w.z);
  }
  context.setPositions(x);
  context.setVelocities(v);
  const double start_energy = context.getState(OpenMM::State::Energy).getPotentialEnergy();
  constexpr int kWarmUp = 10;  // neighbour list and kernels set up
  verlet.step(kWarmUp);
  const Clock::time_point t0 = Clock::now();
  verlet.step(steps);
  const double seconds = seconds_since(t0);
  const double end_energy = context.getState(OpenMM::State::Energy).getPotentialEnergy();
  char what[200];
  std::snprintf(
      what, sizeof what, "%s; unshifted LJ energy per atom %.5g -> %.5g",
      m.rods.empty() ? "Verlet" : ("Verlet, CCMA at tolerance " + number(tolerance)).c_str(),
      start_energy / n, end_energy / n);
  report("OpenMM CPU", n, steps, seconds,
         std::string(what) + "; " + std::to_string(threads) + " thread(s)");
}

// Rods LAMMPS' fix rattle can hold: along each chain, two rods sharing a central bead, then
// one bond left harmonic, so that every cluster is a star of three beads.
std::vector<bool> rattle_clusters(const deli::System& s,
                                  const std::vector<deli::Constraint>& rods) {
  std::vector<bool> taken(s.particles.size(), false), rigid(rods.size(), false);
  for (std::size_t r = 0; r < rods.size(); ++r) {
    const deli::Constraint& a = rods[r];
    if (taken[a.i] || taken[a.j]) continue;
    rigid[r] = true;
    taken[a.i] = true;
    taken[a.j] = true;
    if (r + 1 < rods.size()) {
      const deli::Constraint& b = rods[r + 1];
      const int shared = b.i == a.j || b.i == a.i ? b.i : b.j == a.j || b.j == a.i ? b.j : -1;
      const int other = shared == b.i ? b.j : b.i;
      if (shared >= 0 && !taken[other]) {
        rigid[r + 1] = true;
        taken[other] = true;
        ++r;
      }
    }
  }
  return rigid;
}

void run_lammps(const Model& m, int steps, double free_bond_k) {
  deli::System s = m.start;
  const std::size_t n = s.particles.size();
  std::string what = "fix nve";
  std::string rattle;
  std::vector<double> k = m.bond_k, r0 = m.bond_r0;
  if (!m.rods.empty()) {
    // Bond type 1: left harmonic; type 2: held by fix rattle.
    const std::vector<bool> rigid = rattle_clusters(s, m.rods);
    s.topology.bonds.clear();
    std::size_t held = 0;
    for (std::size_t r = 0; r < m.rods.size(); ++r) {
      s.topology.bonds.push_back({m.rods[r].i, m.rods[r].j, rigid[r] ? 1 : 0});
      held += rigid[r];
    }
    s.topology.bond_types = 2;
    k = {free_bond_k, free_bond_k};
    r0 = {m.rods[0].length, m.rods[0].length};
    rattle = "fix deli_rattle all rattle 1e-10 100 0 b 2";
    char line[300];
    std::snprintf(line, sizeof line,
                  "fix nve + fix rattle (tolerance 1e-10) on %zu of %zu bonds (three-bead "
                  "stars: LAMMPS holds no chain of rods), the rest harmonic K %g",
                  held, m.rods.size(), free_bond_k);
    what = line;
  }
  const std::string data = (std::filesystem::temp_directory_path() /
                            ("deli-peers-" + std::to_string(getpid()) + ".data"))
                               .string();
  deli::write_lammps_data(s, data, "bond", "deli-peers");
  const char* args[] = {"deli-peers", "-screen", "none", "-log", "none", "-nocite"};
  deli::prefer_single_process_mpi();
  void* lmp = lammps_open_no_mpi(6, const_cast<char**>(args), nullptr);
  auto command = [&](const std::string& line) { lammps_command(lmp, line.c_str()); };
  command("units lj");
  command("atom_style bond");
  command("atom_modify map array");
  command("boundary p p p");
  command("read_data " + data);
  std::filesystem::remove(data);
  command("neighbor " + number(m.skin) + " bin");
  command("neigh_modify delay 0 every 1 check yes");
  command("special_bonds lj 0 1 1");
  command("pair_style lj/cut " + number(m.cutoff));
  command("pair_coeff 1 1 " + number(m.epsilon) + " " + number(m.sigma) + " " + number(m.cutoff));
  command("pair_modify shift yes");
  command("bond_style harmonic");
  for (std::size_t t = 0; t < k.size(); ++t) {
    command("bond_coeff " + std::to_string(t + 1) + " " + number(k[t]) + " " + number(r0[t]));
  }
  command("timestep " + number(m.timestep));
  command("fix deli_nve all nve");
  if (!rattle.empty()) {
    if (!lammps_has_style(lmp, "fix", "rattle")) {
      throw std::runtime_error("this LAMMPS has no fix rattle (RIGID package)");
    }
    command(rattle);
  }
  command("thermo_modify norm yes");
  command("run 0");
  const double start_energy = lammps_get_thermo(lmp, "pe");
  const Clock::time_point t0 = Clock::now();
  command("run " + std::to_string(steps));
  const double seconds = seconds_since(t0);
  char energies[100];
  std::snprintf(energies, sizeof energies, "; potential energy per atom %.5g -> %.5g", start_energy,
                lammps_get_thermo(lmp, "pe"));
  const int ranks = lammps_extract_setting(lmp, "world_size");
  const int rank = lammps_extract_setting(lmp, "world_rank");
  lammps_close(lmp);
  if (rank == 0) {
    report("LAMMPS", n, steps, seconds,
           what + energies + "; " + std::to_string(ranks) + " MPI rank(s)");
  }
  lammps_mpi_finalize();
}

}  // namespace

int main(int argc, char** argv) {
  const bool openmm = argc >= 4 && std::string(argv[3]) == "openmm";
  const bool lammps = argc >= 4 && std::string(argv[3]) == "lammps";
  if (!(openmm && argc <= 6) && !(lammps && argc <= 5)) {
    std::fprintf(stderr,
                 "usage: deli-peers INPUT.toml STEPS openmm [CCMA_TOLERANCE [THREADS]]\n"
                 "       deli-peers INPUT.toml STEPS lammps [FREE_BOND_K]\n");
    return 2;
  }
  try {
    const Model model = load_model(argv[1]);
    const int steps = std::stoi(argv[2]);
    if (openmm) {
      run_openmm(model, steps, argc >= 5 ? std::stod(argv[4]) : 1e-4,
                 argc == 6 ? std::stoi(argv[5]) : 1);
    } else {
      run_lammps(model, steps, argc == 5 ? std::stod(argv[4]) : 100.0);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "deli-peers: %s\n", e.what());
    return 1;
  }
  return 0;
}
