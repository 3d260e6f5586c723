// The catalogue of bad inputs and faults (issue 14): each case runs the `deli` binary as a
// user would and asserts its exit status and the words of its one-line message, and where
// it matters that what was written before (the CSV, the previous checkpoint, the inputs)
// survived. The expected messages are those the code under test is written to give: each
// names the file (and line and key, or step and atom) and what to do.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"

namespace deli {
namespace {

struct Case {
  std::string name;
  std::string toml;  // written to DIR/in.toml; @DIR@ becomes the directory
  std::string data;  // written to DIR/in.data when not empty
  int status = 1;    // the expected exit status: 1 input error, 3 simulation stopped (README)
  std::vector<std::string> messages;          // each must appear in the output
  std::string command = "run @DIR@/in.toml";  // deli's arguments
  std::string setup;                          // shell run in DIR first (@DELI@: the deli binary)
  std::string check;                          // shell run in DIR afterwards; must exit 0
  bool tmpfs = false;  // runs in a mount namespace with a small tmpfs at DIR/full
};

// Test names in ctest's output, not the bytes of the struct.
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.name;
}

std::string replaced_all(std::string text, const std::string& from, const std::string& to) {
  for (auto at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

// `from` must occur in `text`: a case that replaces nothing would test the base input.
std::string with(const std::string& text, const std::string& from, const std::string& to) {
  if (text.find(from) == std::string::npos) {
    ADD_FAILURE() << "the base input has no '" << from << "'";
    return text;
  }
  return replaced_all(text, from, to);
}

// --- the base inputs, each valid (the *_runs cases) -----------------------------------------

const std::string kLj = R"([system]
[system.lattice]
type = "fcc"
density = 0.8442
cells = [3, 3, 3]
mass = 1.0

[velocities]
temperature = 1.0
seed = 5

[neighbor]
skin = 0.3

[forcefield.special_bonds]
lj = [0.0, 1.0, 1.0]

[forcefield.pair]
style = "lj/cut"
cutoff = 2.5
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]

[forcefield.external]
gravity = [0.0, 0.0, 0.0]

[integrator]
timestep = 0.005

[run]
steps = 20

[output]
thermo = { every = 5, file = "@DIR@/out.csv" }
)";

const std::string kChains = R"([system]
[system.chains]
count = 20
length = 5
density = 0.3
angles = true
seed = 3

[forcefield.pair]
style = "lj/cut"
cutoff = 2.5
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]

[forcefield.bond]
style = "harmonic"
coeffs = [{ type = 1, k = 30.0, r0 = 1.0 }]

[forcefield.angle]
style = "harmonic"
coeffs = [{ type = 1, k = 5.0, theta0 = 110.0 }]

[minimize]
max_steps = 200
timestep = 0.002

[integrator]
timestep = 0.002

[run]
steps = 20
)";

const std::string kFene = R"([system]
[system.chains]
count = 20
length = 5
density = 0.3
bond_length = 0.97
seed = 3

[forcefield.pair]
style = "wca"
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]

[forcefield.bond]
style = "fene"
coeffs = [{ type = 1, k = 30.0, r0 = 1.5, epsilon = 1.0, sigma = 1.0 }]

[integrator]
timestep = 0.002

[run]
steps = 20
)";

// Two spheres above a floor in an open box, one on a string: walls, anchors, hard spheres.
const std::string kGvi = R"([system]
data = "in.data"
boundary = "fff"

[forcefield.pair]
style = "none"

[forcefield.external]
gravity = [0.0, 0.0, -9.8]

[constraints]
walls = [{ type = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }]
hard_spheres = { diameter = 0.5 }
anchors = [{ atom = 2, point = [2.0, 0.0, 2.0], length = 1.0 }]

[neighbor]
skin = 0.5

[integrator]
type = "gvi"
timestep = 0.01

[run]
steps = 20
)";

const std::string kTwoAtoms = R"(two atoms

2 atoms
1 atom types

-5.0 5.0 xlo xhi
-5.0 5.0 ylo yhi
-5.0 5.0 zlo zhi

Masses

1 1.0

Atoms # atomic

1 1 0.0 0.0 1.0
2 1 2.0 0.0 1.0
)";

// 108 atoms of the LJ lattice as a data file (the LAMMPS reader's cases).
const std::string kLjData = R"([system]
data = "in.data"

[forcefield.pair]
style = "lj/cut"
cutoff = 1.2
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]

[integrator]
timestep = 0.005

[run]
steps = 10

[output]
thermo = { every = 5, file = "@DIR@/out.csv" }
)";

const std::string kSmallData = R"(small

4 atoms
1 atom types

0.0 3.0 xlo xhi
0.0 3.0 ylo yhi
0.0 3.0 zlo zhi

Masses

1 1.0

Atoms # atomic

1 1 0.5 0.5 0.5
2 1 1.6 0.5 0.5
3 1 0.5 1.6 0.5
4 1 0.5 0.5 1.6

Velocities

1 0.1 0.0 0.0
2 0.0 0.1 0.0
3 0.0 0.0 0.1
4 -0.1 -0.1 -0.1
)";

// The melt's 4000 atoms: large enough frames to fill a small tmpfs quickly.
const std::string kMelt = std::string(R"([system]
data = ")") + DELI_SOURCE_DIR +
                          R"(/inputs/lj_chains/melt.data"

[forcefield.special_bonds]
lj = [0.0, 1.0, 1.0]

[forcefield.pair]
style = "wca"
coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 1.0 }]

[forcefield.bond]
style = "fene"
coeffs = [{ type = 1, k = 30.0, r0 = 1.5, epsilon = 1.0, sigma = 1.0 }]

[integrator]
timestep = 0.005

[run]
steps = 400
)";

// The CSV holds a header and whole rows, none of them NaN: what was written is kept.
const std::string kCsvIntact =
    "head -1 out.csv | grep -q '^step,' && ! grep -qi nan out.csv && "
    "test \"$(tail -c 1 out.csv | od -An -c | tr -d ' ')\" = '\\n'";

// --- the cases ------------------------------------------------------------------------------

void non_finite_cases(std::vector<Case>& cases) {
  struct Key {
    std::string name, base, from, to_prefix, to_suffix, key;
    std::string data;
  };
  // `to_prefix + value + to_suffix` replaces `from`.
  const std::vector<Key> keys{
      {"skin", kLj, "skin = 0.3", "skin = ", "", "'neighbor.skin'"},
      {"timestep", kLj, "timestep = 0.005", "timestep = ", "", "'integrator.timestep'"},
      {"epsilon", kLj, "epsilon = 1.0", "epsilon = ", "", "'forcefield.pair.coeffs[1].epsilon'"},
      {"sigma", kLj, "sigma = 1.0", "sigma = ", "", "'forcefield.pair.coeffs[1].sigma'"},
      {"cutoff", kLj, "cutoff = 2.5", "cutoff = ", "", "'forcefield.pair.cutoff'"},
      {"special_bonds", kLj, "lj = [0.0, 1.0, 1.0]", "lj = [0.0, ", ", 1.0]",
       "'forcefield.special_bonds.lj'"},
      {"gravity", kLj, "gravity = [0.0, 0.0, 0.0]", "gravity = [0.0, 0.0, ", "]",
       "'forcefield.external.gravity'"},
      {"temperature", kLj, "temperature = 1.0", "temperature = ", "", "'velocities.temperature'"},
      {"density", kLj, "density = 0.8442", "density = ", "", "'system.lattice.density'"},
      {"mass", kLj, "mass = 1.0", "mass = ", "", "'system.lattice.mass'"},
      {"bond_k", kChains, "k = 30.0", "k = ", "", "'forcefield.bond.coeffs[1].k'"},
      {"bond_r0", kChains, "r0 = 1.0", "r0 = ", "", "'forcefield.bond.coeffs[1].r0'"},
      {"angle_k", kChains, "k = 5.0", "k = ", "", "'forcefield.angle.coeffs[1].k'"},
      {"theta0", kChains, "theta0 = 110.0", "theta0 = ", "", "'forcefield.angle.coeffs[1].theta0'"},
      {"chain_density", kChains, "density = 0.3", "density = ", "", "'system.chains.density'"},
      {"minimize_timestep", kChains, "timestep = 0.002\n\n[integrator]",
       "timestep = ", "\n\n[integrator]", "'minimize.timestep'"},
      {"fene_epsilon", kFene, "r0 = 1.5, epsilon = 1.0", "r0 = 1.5, epsilon = ", "",
       "'forcefield.bond.coeffs[1].epsilon'"},
      {"fene_k", kFene, "k = 30.0", "k = ", "", "'forcefield.bond.coeffs[1].k'"},
      {"wall_normal", kGvi, "normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, ", "]",
       "'constraints.walls[1].normal'", kTwoAtoms},
      {"wall_point", kGvi, "point = [0.0, 0.0, 0.0]", "point = [0.0, 0.0, ", "]",
       "'constraints.walls[1].point'", kTwoAtoms},
      {"diameter", kGvi, "diameter = 0.5", "diameter = ", "", "'constraints.hard_spheres.diameter'",
       kTwoAtoms},
      {"anchor_length", kGvi, "length = 1.0", "length = ", "", "'constraints.anchors[1].length'",
       kTwoAtoms},
      {"anchor_point", kGvi, "point = [2.0, 0.0, 2.0]", "point = [2.0, ", ", 2.0]",
       "'constraints.anchors[1].point'", kTwoAtoms},
  };
  for (const Key& k : keys) {
    for (const auto& [label, value] :
         std::vector<std::pair<std::string, std::string>>{{"nan", "nan"}, {"inf", "inf"}}) {
      cases.push_back({"nonfinite_" + k.name + "_" + label,
                       with(k.base, k.from, k.to_prefix + value + k.to_suffix),
                       k.data,
                       1,
                       {"in.toml:", k.key, "expected a finite number, found " + label}});
    }
  }
  // Negative infinity and NaN with a sign read the same way.
  cases.push_back({"nonfinite_skin_minus_inf",
                   with(kLj, "skin = 0.3", "skin = -inf"),
                   "",
                   1,
                   {"'neighbor.skin'", "found inf"}});
  cases.push_back({"nonfinite_timestep_minus_nan",
                   with(kLj, "timestep = 0.005", "timestep = -nan"),
                   "",
                   1,
                   {"'integrator.timestep'", "found nan"}});
  // Finite numbers that make an infinite box.
  cases.push_back({"overflow_lattice_box",
                   with(kLj, "density = 0.8442", "density = 1e-320"),
                   "",
                   1,
                   {"in.toml:", "box length along x is inf", "density"}});
}

void data_file_cases(std::vector<Case>& cases) {
  auto data_case = [&](const std::string& name, const std::string& from, const std::string& to,
                       const std::vector<std::string>& messages) {
    cases.push_back({"data_" + name, kLjData, with(kSmallData, from, to), 1, messages});
  };
  data_case("nan_x", "2 1 1.6 0.5 0.5", "2 1 nan 0.5 0.5",
            {"in.data:", "expected a finite number for x of atom 2", "'nan'"});
  data_case("inf_z", "3 1 0.5 1.6 0.5", "3 1 0.5 1.6 inf",
            {"in.data:", "expected a finite number for z of atom 3"});
  data_case("nan_mass", "1 1.0\n\nAtoms", "1 nan\n\nAtoms",
            {"in.data:", "the mass of atom type 1"});
  data_case("inf_mass", "1 1.0\n\nAtoms", "1 inf\n\nAtoms",
            {"in.data:", "the mass of atom type 1"});
  data_case("nan_velocity", "2 0.0 0.1 0.0", "2 0.0 nan 0.0", {"in.data:", "finite number"});
  data_case("inf_velocity", "4 -0.1 -0.1 -0.1", "4 -0.1 -0.1 -inf", {"in.data:", "finite number"});
  data_case("nan_box", "0.0 3.0 ylo yhi", "nan 3.0 ylo yhi", {"in.data:", "ylo"});
  data_case("inf_box", "0.0 3.0 zlo zhi", "0.0 inf zlo zhi", {"in.data:", "zhi"});
  data_case("overflowing_box", "0.0 3.0 xlo xhi", "-1e308 1e308 xlo xhi",
            {"in.toml:", "box length along x is inf"});
  data_case("huge_coordinate", "1 1 0.5 0.5 0.5", "1 1 1e400 0.5 0.5",
            {"in.data:", "expected a finite number for x of atom 1"});
}

void run_time_cases(std::vector<Case>& cases) {
  const std::string stopped = "simulation stopped: step ";
  cases.push_back({"runs_lj", kLj, "", 0, {"loop time"}, "run @DIR@/in.toml", "", kCsvIntact});
  cases.push_back({"runs_chains", kChains, "", 0, {"loop time"}});
  cases.push_back({"runs_fene", kFene, "", 0, {"loop time"}});
  cases.push_back({"runs_gvi", kGvi, kTwoAtoms, 0, {"loop time"}});
  cases.push_back({"runs_from_data", kLjData, kSmallData, 0, {"loop time"}});
  // A timestep far too large: the positions go to infinity and NaN within steps.
  cases.push_back(
      {"blowup_huge_timestep",
       with(with(kLj, "timestep = 0.005", "timestep = 0.5"), "steps = 20", "steps = 5000"),
       "",
       3,  // the simulation stopped
       {stopped, "atom ", "the run blew up", "timestep"},
       "run @DIR@/in.toml",
       "",
       kCsvIntact + " && test $(wc -l < out.csv) -lt 10"});
  cases.push_back(
      {"blowup_huge_timestep_no_thermo",
       with(with(with(kLj, "timestep = 0.005", "timestep = 0.5"), "steps = 20", "steps = 5000"),
            "every = 5,", "every = 0,"),
       "",
       3,  // the simulation stopped
       {stopped, "atom ", "the run blew up"}});
  cases.push_back({"blowup_verlet_dt_2",
                   with(kLj, "timestep = 0.005", "timestep = 2.0"),
                   "",
                   3,  // the simulation stopped
                   {stopped, "ran away (far beyond the box)"}});
  // Two atoms on top of each other: the pair force at r = 0 is not finite at step 0.
  cases.push_back({"blowup_overlapping_atoms",
                   kLjData,
                   with(kSmallData, "2 1 1.6 0.5 0.5", "2 1 0.5 0.5 0.5"),
                   3,  // the simulation stopped
                   {"simulation stopped: step 0", "energy is not finite", "atom 1"}});
  cases.push_back({"blowup_huge_epsilon",
                   with(kLj, "epsilon = 1.0", "epsilon = 1e308"),
                   "",
                   3,  // the simulation stopped
                   {"simulation stopped: step 0", "energy is not finite"}});
  cases.push_back({"blowup_huge_gravity",
                   with(kLj, "gravity = [0.0, 0.0, 0.0]", "gravity = [0.0, 0.0, 1e307]"),
                   "",
                   3,  // the simulation stopped
                   {stopped, "not finite"}});
  cases.push_back({"blowup_huge_temperature",
                   with(kLj, "temperature = 1.0", "temperature = 1e308"),
                   "",
                   1,
                   {"in.toml:1: atom 1 has a position or velocity that is not finite"}});
  cases.push_back({"blowup_keeps_trajectory",
                   with(with(kLj, "timestep = 0.005", "timestep = 0.5"), "[output]\n",
                        "[output]\ntrajectory = { file = \"@DIR@/out.h5\", every = 1 }\n"),
                   "",
                   3,  // the simulation stopped
                   {stopped, "the run blew up"},
                   "run @DIR@/in.toml",
                   "",
                   "/usr/bin/python3 -c \"import h5py, numpy; f = h5py.File('out.h5'); "
                   "x = f['particles/all/position/value'][:]; assert len(x) >= 2 and "
                   "numpy.isfinite(x).all(), x.shape\""});
}

void write_failure_cases(std::vector<Case>& cases) {
  // /dev/full refuses every write with ENOSPC: a full disk without mounting anything.
  cases.push_back({"full_thermo_csv",
                   with(kLj, "@DIR@/out.csv", "/dev/full"),
                   "",
                   3,  // the simulation stopped
                   {"/dev/full: could not write the thermo row of step 0", "disk full"}});
  cases.push_back(
      {"full_dump",
       with(kLj, "[output]\n", "[output]\ndump = { file = \"/dev/full\", every = 5 }\n"),
       "",
       3,  // the simulation stopped
       {"/dev/full: could not write the frame of step 0", "disk full"}});
  cases.push_back({"full_stdout",
                   kLj,
                   "",
                   1,
                   {"could not write the thermo table to standard output", "disk full"},
                   "run @DIR@/in.toml > /dev/full 2> err.txt || (cat err.txt; exit 1)"});
  cases.push_back({"unwritable_thermo_dir",
                   with(kLj, "@DIR@/out.csv", "@DIR@/missing/out.csv"),
                   "",
                   1,
                   {"cannot open the thermo file", "directory exists"}});
  cases.push_back({"unwritable_trajectory_dir",
                   with(kLj, "[output]\n",
                        "[output]\ntrajectory = { file = \"@DIR@/missing/t.h5\", every = 5 }\n"),
                   "",
                   1,
                   {"cannot create the trajectory file"}});
  cases.push_back({"unwritable_checkpoint_dir",
                   with(kLj, "[output]\n",
                        "[output]\ncheckpoint = { file = \"@DIR@/missing/c.h5\", every = 5 }\n"),
                   "",
                   3,  // the simulation stopped
                   {"cannot create the checkpoint file"}});

  // A small tmpfs that fills up during the run. Exit 1 with the message, never a crash
  // (HDF5's exit handler used to die with SIGSEGV), and the records before it kept whole.
  const std::string csv_full =
      kMelt + "\n[output]\nthermo = { every = 1, file = \"@DIR@/full/out.csv\" }\n";
  cases.push_back({"tmpfs_full_thermo_csv",
                   csv_full,
                   "",
                   3,  // the simulation stopped
                   {"full/out.csv: could not write the thermo row of step", "disk full"},
                   "run @DIR@/in.toml",
                   "dd if=/dev/zero of=full/ballast bs=1k count=1150 2>/dev/null",
                   "cd full && " + kCsvIntact,
                   true});
  for (const std::string& size : {"100", "300", "900"}) {
    cases.push_back(
        {"tmpfs_full_trajectory_" + size + "k",
         kMelt + "\n[output]\ntrajectory = { file = \"@DIR@/full/out.h5\", every = 10 }\n",
         "",
         3,  // the simulation stopped
         {"full/out.h5: HDF5 failed to", "disk full"},
         "run @DIR@/in.toml",
         "dd if=/dev/zero of=full/ballast bs=1k count=" + std::string(size) + " 2>/dev/null",
         "",
         true});
  }
  cases.push_back({"tmpfs_full_dump",
                   kMelt + "\n[output]\ndump = { file = \"@DIR@/full/out.dump\", every = 10 }\n",
                   "",
                   3,  // the simulation stopped
                   {"full/out.dump: could not write the frame of step", "disk full"},
                   "run @DIR@/in.toml",
                   "",
                   "cd full && grep -c 'ITEM: TIMESTEP' out.dump",
                   true});
  // The first checkpoint fits, its replacement does not: the run stops, the first one stays
  // and restarts.
  cases.push_back(
      {"tmpfs_full_checkpoint_keeps_previous",
       kMelt + "\n[output]\ncheckpoint = { file = \"@DIR@/full/out.chk\", every = 100 }\n",
       "",
       3,  // the simulation stopped
       {"full/out.chk.partial: could not write the checkpoint", "the previous checkpoint",
        "is kept"},
       "run @DIR@/in.toml",
       "dd if=/dev/zero of=full/ballast bs=1k count=650 2>/dev/null",
       "test ! -e full/out.chk.partial && rm full/ballast && " DELI_BINARY
       " run in.toml --restart full/out.chk | grep -q 'for 300 steps'",
       true});
}

void checkpoint_cases(std::vector<Case>& cases) {
  const std::string input =
      with(kLj, "[output]\n", "[output]\ncheckpoint = { file = \"@DIR@/c.h5\", every = 10 }\n");
  const std::string longer = with(input, "steps = 20", "steps = 40");
  // Writes c.h5 at step 20 with the input as it is, then the case's input restarts from it.
  const std::string first_run = DELI_BINARY " run first.toml > /dev/null && ";
  auto restart_case = [&](const std::string& name, const std::string& damage,
                          const std::vector<std::string>& messages, const std::string& toml) {
    cases.push_back({"checkpoint_" + name, toml, "", 1, messages,
                     "run @DIR@/in.toml --restart @DIR@/c.h5",
                     "printf '%s' '" + replaced_all(input, "'", "'\\''") + "' > first.toml && " +
                         first_run + damage});
  };
  const std::string forge =
      "/usr/bin/python3 " DELI_SOURCE_DIR "/tests/errors/forge_checkpoint.py c.h5 ";
  restart_case("restarts", "true", {}, longer);
  cases.back().status = 0;
  cases.back().messages = {"for 20 steps"};
  restart_case("nan_position", forge + "position 7 nan",
               {"c.h5: the checkpoint's 'position' holds a value that is not finite"}, longer);
  restart_case("inf_velocity", forge + "velocity 0 inf", {"'velocity'", "not finite"}, longer);
  restart_case("nan_build_positions", forge + "neighbor_build_positions 3 nan",
               {"'neighbor_build_positions'", "not finite"}, longer);
  restart_case("negative_step", forge + "step 0 -5", {"'step' is negative"}, longer);
  restart_case("nan_time", forge + "time 0 nan", {"'time' is not a finite"}, longer);
  restart_case("negative_time", forge + "time 0 -1", {"'time' is not a finite"}, longer);
  restart_case("changed_position_without_checksum",
               "/usr/bin/python3 -c \"import h5py; f = h5py.File('c.h5', 'r+'); "
               "f['position'][0, 0] += 1e-9\"",
               {"'position' does not match its checksum"}, longer);
  restart_case(
      "changed_step_without_checksum",
      "/usr/bin/python3 -c \"import h5py; f = h5py.File('c.h5', 'r+'); f['step'][0] = 30\"",
      {"'step' does not match its checksum"}, longer);
  restart_case("changed_state_without_checksum",
               "/usr/bin/python3 -c \"import h5py; f = h5py.File('c.h5', 'r+'); "
               "f['velocity'][5, 2] = 0.0\"",
               {"'velocity' does not match its checksum"}, longer);
  restart_case("missing_checksum",
               "/usr/bin/python3 -c \"import h5py; f = h5py.File('c.h5', 'r+'); "
               "del f['image'].attrs['fnv1a64']\"",
               {"'image' has no checksum"}, longer);
  restart_case(
      "missing_dataset",
      "/usr/bin/python3 -c \"import h5py; f = h5py.File('c.h5', 'r+'); del f['velocity']\"",
      {"'velocity' is missing"}, longer);
  restart_case("truncated", "truncate -s 2000 c.h5", {"c.h5", "checkpoint"}, longer);
  restart_case("empty", ": > c.h5", {"c.h5: not a deli checkpoint"}, longer);
  restart_case("text", "echo hello > c.h5", {"c.h5 exists and is not a checkpoint"}, longer);
  restart_case("directory", "rm c.h5 && mkdir c.h5", {"c.h5"}, longer);
  restart_case("missing", "rm c.h5", {"c.h5: not a deli checkpoint (missing"}, longer);
  restart_case("flipped_byte_in_positions",
               "/usr/bin/python3 -c \"import h5py; f = h5py.File('c.h5'); "
               "o = f['position'].id.get_offset(); f.close(); "
               "b = bytearray(open('c.h5', 'rb').read()); b[o + 100] ^= 0x10; "
               "open('c.h5', 'wb').write(b)\"",
               {"'position' does not match its checksum"}, longer);
  // Foreign checkpoints with the same atom count (the ids match): the fingerprint differs.
  const std::string foreign = "refuses a foreign";
  restart_case("foreign_mass", "true", {"c.h5: the checkpoint belongs to another system"},
               with(longer, "mass = 1.0", "mass = 2.0"));
  restart_case("foreign_density", "true", {"belongs to another system"},
               with(longer, "density = 0.8442", "density = 0.8"));
  restart_case("foreign_epsilon", "true", {"belongs to another system", "[forcefield]"},
               with(longer, "epsilon = 1.0", "epsilon = 0.5"));
  restart_case("foreign_cutoff", "true", {"belongs to another system"},
               with(longer, "cutoff = 2.5", "cutoff = 2.4"));
  restart_case("foreign_special_bonds", "true", {"belongs to another system"},
               with(longer, "lj = [0.0, 1.0, 1.0]", "lj = [0.0, 0.5, 1.0]"));
  restart_case("foreign_boundary", "true", {"belongs to another system"},
               with(longer, "[system]\n", "[system]\nboundary = \"ppf\"\n"));
  restart_case("foreign_atom_count", "true", {"c.h5: the checkpoint holds 108 atoms"},
               with(longer, "cells = [3, 3, 3]", "cells = [3, 3, 4]"));
  restart_case("already_at_the_end", "true", {"c.h5: the checkpoint is at step 20"}, input);
  // What may change on a restart: the run's length and its outputs (fingerprint unchanged).
  restart_case("other_outputs_restart", "true", {}, with(longer, "every = 5,", "every = 4,"));
  cases.back().status = 0;
}

void output_path_cases(std::vector<Case>& cases) {
  auto output_case = [&](const std::string& name, const std::string& outputs,
                         const std::vector<std::string>& messages, const std::string& setup = "",
                         const std::string& command = "run @DIR@/in.toml") {
    cases.push_back({"paths_" + name, kLjData + outputs, kSmallData, 1, messages, command,
                     setup + (setup.empty() ? "" : " && ") +
                         "cp in.toml in.toml.orig && cp in.data in.data.orig",
                     "cmp in.toml in.toml.orig && cmp in.data in.data.orig"});
  };
  output_case("thermo_is_input", "dump = { file = \"@DIR@/in.toml\" }\n",
              {"in.toml is the run's input file", "name another file"});
  output_case("thermo_is_input_relative", "dump = { file = \"@DIR@/./sub/../in.toml\" }\n",
              {"is the run's input file"}, "mkdir -p sub");
  output_case("trajectory_is_input", "trajectory = { file = \"@DIR@/in.toml\" }\n",
              {"is the run's input file", "trajectory"});
  output_case("checkpoint_is_input", "checkpoint = { file = \"@DIR@/in.toml\" }\n",
              {"is the run's input file", "checkpoint"});
  output_case("dump_is_data", "dump = { file = \"@DIR@/in.data\" }\n",
              {"in.data is the run's data file", "dump"});
  output_case("trajectory_is_data", "trajectory = { file = \"@DIR@/in.data\" }\n",
              {"is the run's data file"});
  output_case("checkpoint_is_data", "checkpoint = { file = \"@DIR@/in.data\" }\n",
              {"is the run's data file"});
  output_case("dump_is_data_by_symlink", "dump = { file = \"@DIR@/link.data\" }\n",
              {"link.data is the run's data file"}, "ln -s in.data link.data");
  output_case("dump_and_thermo_one_file", "dump = { file = \"@DIR@/out.csv\" }\n",
              {"'output.dump.file'", "is also the thermo output"});
  output_case("trajectory_and_dump_one_file",
              "dump = { file = \"@DIR@/x\" }\ntrajectory = { file = \"@DIR@/x\" }\n",
              {"is also the dump output"});
  output_case("checkpoint_and_trajectory_one_file",
              "checkpoint = { file = \"@DIR@/x.h5\" }\ntrajectory = { file = \"@DIR@/x.h5\" }\n",
              {"is also the checkpoint output"});
  output_case(
      "trajectory_is_checkpoint_aside",
      "checkpoint = { file = \"@DIR@/x.h5\" }\ntrajectory = { file = \"@DIR@/x.h5.partial\" }\n",
      {"is also the checkpoint output"});
  output_case("checkpoint_is_device", "checkpoint = { file = \"/dev/full\" }\n",
              {"/dev/full exists and is not a regular file"});
  output_case("checkpoint_is_null", "checkpoint = { file = \"/dev/null\" }\n",
              {"/dev/null exists and is not a regular file"});
  output_case("checkpoint_is_symlink", "checkpoint = { file = \"@DIR@/link.h5\" }\n",
              {"link.h5 exists and is not a regular file"}, "touch target && ln -s target link.h5");
  output_case("checkpoint_is_directory", "checkpoint = { file = \"@DIR@/sub\" }\n",
              {"sub exists and is not a regular file"}, "mkdir sub");
  output_case("checkpoint_is_text", "checkpoint = { file = \"@DIR@/notes.txt\" }\n",
              {"notes.txt exists and is not a checkpoint"}, "echo keep > notes.txt");
  cases.back().check += " && grep -q keep notes.txt";
  output_case("write_data_over_input", "", {"in.toml: is the input's own input file"}, "",
              "write-data @DIR@/in.toml @DIR@/in.toml");
  output_case("write_data_over_data", "", {"is the input's own data file"}, "",
              "write-data @DIR@/in.toml @DIR@/in.data");
  output_case("write_data_over_data_relative", "", {"is the input's own data file"}, "",
              "write-data @DIR@/in.toml @DIR@/./in.data");
  output_case("restart_from_thermo_file", "", {"is also an output of the input"}, "",
              "run @DIR@/in.toml --restart @DIR@/out.csv");
  // A checkpoint over its own earlier checkpoint is what checkpoints do.
  cases.push_back({"paths_checkpoint_over_checkpoint",
                   kLjData + "checkpoint = { file = \"@DIR@/c.h5\", every = 5 }\n",
                   kSmallData,
                   0,
                   {"loop time"},
                   "run @DIR@/in.toml",
                   DELI_BINARY " run in.toml > /dev/null"});
}

// Messages that used to mislead (issue 14, item 8): each now names what is wrong.
void message_cases(std::vector<Case>& cases) {
  cases.push_back({"split_small_loops_not_a_boolean",
                   with(kLj, "steps = 20", "steps = 20\nsplit_small_loops = \"yes\""),
                   "",
                   1,
                   {"in.toml:", "'run.split_small_loops'", "expected true or false"}});
  cases.push_back({"input_is_a_directory",
                   kLj,
                   "",
                   1,
                   {"is a directory, not an input file"},
                   "run @DIR@/sub",
                   "mkdir -p sub"});
  cases.push_back({"data_title_only",
                   kLjData,
                   "title only\n",
                   1,
                   {"in.data", "no 'N atoms' header line", "empty or not a LAMMPS data file"}});
  cases.push_back({"data_empty_file", kLjData, "\n", 1, {"in.data", "no 'N atoms' header line"}});
  cases.push_back({"lattice_cells_overflow_int",
                   with(kLj, "cells = [3, 3, 3]", "cells = [1e10, 1, 1]"),
                   "",
                   1,
                   {"in.toml:", "'system.lattice.cells'", "at most 1000000 cells per axis"}});
  cases.push_back({"lattice_atoms_overflow_int",
                   with(kLj, "cells = [3, 3, 3]", "cells = [1000000, 1000, 1]"),
                   "",
                   1,
                   {"in.toml:", "more than deli's limit of 2147483647 atoms"}});
  cases.push_back({"chain_count_overflow_int",
                   with(kChains, "count = 20", "count = 4294967396"),
                   "",
                   1,
                   {"in.toml:", "4294967396 chains of 5 atoms", "more than deli's limit"}});
  cases.push_back({"shadow_reflections_with_angles",
                   with(with(with(kChains, "[integrator]\n",
                                  "[constraints]\nhard_spheres = { "
                                  "diameter = 0.8 }\n[integrator]\n"
                                  "type = \"gvi\"\n"),
                             "timestep = 0.002\n\n[run]",
                             "timestep = 0.002\nreflection = { energy = \"shadow\" }\n\n[run]"),
                        "[minimize]\nmax_steps = 200\ntimestep = 0.002\n\n", ""),
                   "",
                   1,
                   {"in.toml:", "'integrator.reflection.energy'", "harmonic angles lack",
                    "energy = \"hamiltonian\""}});
  for (const auto& [name, length] : {std::pair{"zero", "0.0"}, std::pair{"negative", "-1.0"}}) {
    cases.push_back(
        {std::string("rod_length_") + name,
         with(kGvi, "[neighbor]",
              std::string("rods = [{ atoms = [1, 2], length = ") + length + " }]\n\n[neighbor]"),
         kTwoAtoms,
         1,
         {"in.toml:", "'constraints.rods[1].length'", "must be positive"}});
  }
  // [constraints]: every refusal of constraints_input.cpp, each naming its key.
  const std::string two_spheres_periodic = with(kGvi, "boundary = \"fff\"", "boundary = \"ppp\"");
  for (const Case& c : std::vector<Case>{
           {"constraints_rod_unknown_atom",
            with(kGvi, "[neighbor]", "rods = [{ atoms = [1, 7] }]\n\n[neighbor]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.rods[1].atoms'", "no atom with id 7"}},
           {"constraints_rod_fractional_atom",
            with(kGvi, "[neighbor]", "rods = [{ atoms = [1, 1.5] }]\n\n[neighbor]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.rods[1].atoms'", "no atom with id 1"}},
           {"constraints_rod_same_atom",
            with(kGvi, "[neighbor]", "rods = [{ atoms = [2, 2] }]\n\n[neighbor]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.rods[1].atoms'", "two different atoms"}},
           {"constraints_rigid_rod_length_zero",
            with(kFene, "[integrator]\n",
                 "[constraints]\nbonds = \"rigid\"\nrod_length = 0.0\n\n[integrator]\n"),
            "",
            1,
            {"in.toml:", "'constraints.rod_length'", "must be positive"}},
           {"constraints_anchor_unknown_atom",
            with(kGvi, "atom = 2,", "atom = 3,"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.anchors[1].atom'", "no atom with id 3"}},
           {"constraints_anchor_length_zero",
            with(kGvi, "length = 1.0 }]", "length = 0.0 }]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.anchors[1].length'", "must be positive"}},
           {"constraints_diameter_negative",
            with(kGvi, "diameter = 0.5", "diameter = -0.5"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.hard_spheres.diameter'", "must be positive"}},
           {"constraints_radii_zero",
            with(kGvi, "diameter = 0.5", "radii = [0.0]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.hard_spheres.radii'", "must be positive"}},
           {"constraints_radii_count",
            with(kGvi, "diameter = 0.5", "radii = [0.2, 0.3]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.hard_spheres.radii'"}},
           {"constraints_wall_normal_not_unit",
            with(kGvi, "normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, 2.0]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.walls[1].normal'", "must be a unit vector",
             "its length is 2"}},
           {"constraints_wall_type_unknown",
            with(kGvi, "type = \"plane\"", "type = \"cylinder\""),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.walls[1].type'", "plane"}},
           {"constraints_plane_wall_periodic",
            with(two_spheres_periodic,
                 "anchors = [{ atom = 2, "
                 "point = [2.0, 0.0, 2.0], length = 1.0 }]\n",
                 ""),
            kTwoAtoms,
            1,
            {"in.toml:", "a plane wall needs the box open along z"}},
           {"constraints_sphere_wall_radius_zero",
            with(kGvi,
                 "walls = [{ type = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, "
                 "1.0] }]",
                 "walls = [{ type = \"inside_sphere\", radius = 0.0 }]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.walls[1].radius'", "must be positive"}},
           {"constraints_tolerance_zero",
            with(kGvi, "[neighbor]", "tolerance = { gap = 0.0 }\n\n[neighbor]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.tolerance.gap'", "must be positive"}},
           {"constraints_unknown_key",
            with(kGvi, "[neighbor]", "rod = 1.0\n\n[neighbor]"),
            kTwoAtoms,
            1,
            {"in.toml:", "'constraints.rod'"}},
       }) {
    cases.push_back(c);
  }
  // Found by fuzzing (tools/fuzz.sh toml_input): beads no closer than min_distance >=
  // bond_length cannot form a chain, and the builder spent seconds on every try first.
  cases.push_back({"chains_min_distance_not_below_bond_length",
                   with(kFene, "bond_length = 0.97\n", "bond_length = 0.97\nmin_distance = 1.96\n"),
                   "",
                   1,
                   {"in.toml:", "'system.chains.min_distance'", "must be less than bond_length"}});
  cases.push_back({"fene_k_negative",
                   with(kFene, "k = 30.0", "k = -30.0"),
                   "",
                   1,
                   {"in.toml:", "'forcefield.bond.coeffs[1].k'", "must be a positive number"}});
  cases.push_back({"fene_k_zero",
                   with(kFene, "k = 30.0", "k = 0.0"),
                   "",
                   1,
                   {"'forcefield.bond.coeffs[1].k'", "must be a positive number"}});
  cases.push_back({"fene_r0_below_bond_length",
                   with(kFene, "r0 = 1.5", "r0 = 0.9"),
                   "",
                   3,
                   {"stretched to r = 0.97", "bond type 1", "already at the start", "larger r0"}});
  cases.push_back({"fene_r0_zero",
                   with(kFene, "r0 = 1.5", "r0 = 0.0"),
                   "",
                   1,
                   {"'forcefield.bond.coeffs[1].r0'", "must be a positive number"}});
  cases.push_back({"bond_sigma_negative",
                   with(kFene, "sigma = 1.0 }]\n\n[integrator]", "sigma = -1.0 }]\n\n[integrator]"),
                   "",
                   1,
                   {"'forcefield.bond.coeffs[1].sigma'", "must be a positive number"}});
  cases.push_back({"thermostat_damping_zero",
                   kLj + "\n[thermostat]\ntype = \"langevin\"\ntemperature = 1.0\ndamping = 0.0\n"
                         "seed = 1\n",
                   "",
                   1,
                   {"in.toml:", "'thermostat.damping'", "must be a positive time"}});
  cases.push_back({"thermostat_unknown_type",
                   kLj + "\n[thermostat]\ntype = \"berendsen\"\ntemperature = 1.0\ndamping = 1.0\n"
                         "seed = 1\n",
                   "",
                   1,
                   {"in.toml:", "'thermostat.type'", "berendsen"}});
  cases.push_back({"negative_sort_every",
                   with(kLj, "skin = 0.3", "skin = 0.3\nsort_every = -5"),
                   "",
                   1,
                   {"in.toml:", "'neighbor.sort_every'", "must not be negative", "0: never"}});
  cases.push_back({"thermostat_negative_seed",
                   kLj + "\n[thermostat]\ntype = \"csvr\"\ntemperature = 1.0\ndamping = 1.0\n"
                         "seed = -4\n",
                   "",
                   1,
                   {"'thermostat.seed'", "must not be negative"}});
  // kFene's chains are 1-2-3-4-5, 6-7-..., with bonds along each.
  const std::string gvi_chains = with(kFene, "[integrator]\n", "[integrator]\ntype = \"gvi\"\n");
  cases.push_back(
      {"rods_break_triangle_inequality",
       with(gvi_chains, "[integrator]",
            "[constraints]\nrods = [{ atoms = [1, 2], length = 1.0 }, { atoms = [2, 3], "
            "length = 1.0 }, { atoms = [1, 3], length = 3.0 }]\n\n[integrator]"),
       "",
       1,
       {"in.toml:", "'constraints.rods'", "infeasible constraints", "atoms 1, 2 and 3",
        "cannot form a triangle"}});
  cases.push_back({"rod_given_twice",
                   with(with(gvi_chains, "[integrator]",
                             "[constraints]\nbonds = \"rigid\"\nrods = [{ atoms = [2, 1] }]\n\n"
                             "[integrator]"),
                        "[forcefield.bond]\nstyle = \"fene\"\ncoeffs = [{ type = 1, k = 30.0, r0 = "
                        "1.5, epsilon = 1.0, sigma = 1.0 }]\n",
                        ""),
                   "",
                   1,
                   {"in.toml:", "infeasible constraints", "atoms 1 and 2 are joined by two rods"}});
  cases.push_back(
      {"restart_csv_damaged",
       with(kLj, "[output]\n", "[output]\ncheckpoint = { file = \"@DIR@/c.h5\", every = 10 }\n"),
       "",
       1,
       {"out.csv:3", "no readable step", "damaged"},
       "run @DIR@/in.toml --restart @DIR@/c.h5",
       "@DELI@ run @DIR@/in.toml > /dev/null && sed -i 's/steps = 20/steps = 40/' "
       "in.toml && sed -i '3s/^[0-9]*/xx/' out.csv"});
}

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  message_cases(cases);
  non_finite_cases(cases);
  data_file_cases(cases);
  run_time_cases(cases);
  write_failure_cases(cases);
  checkpoint_cases(cases);
  output_path_cases(cases);
  return cases;
}

bool can_mount_tmpfs(const std::string& dir, std::string& why) {
  const testing::ShellResult r = testing::run_shell("mkdir -p " + dir +
                                                    "/probe && unshare -m sh -c 'mount -t tmpfs -o "
                                                    "size=64k tmpfs " +
                                                    dir + "/probe'");
  why = r.output;
  return r.status == 0;
}

class Catalogue : public ::testing::TestWithParam<Case> {};

TEST_P(Catalogue, ExitStatusAndMessage) {
  const Case& c = GetParam();
  const std::string dir = deli::testing::process_temp_dir() + "/catalogue/" + c.name;
  ASSERT_EQ(testing::run_shell("rm -rf " + dir + " && mkdir -p " + dir + "/full").status, 0);
  if (c.tmpfs) {
    std::string why;
    if (!can_mount_tmpfs(dir, why)) {
      GTEST_SKIP() << "cannot mount a tmpfs here (needs root and unshare -m): " << why;
    }
  }
  std::ofstream(dir + "/in.toml") << replaced_all(c.toml, "@DIR@", dir);
  if (!c.data.empty()) std::ofstream(dir + "/in.data") << c.data;
  const std::string args = replaced_all(c.command, "@DIR@", dir);
  std::string command = "cd " + dir + " && ";
  if (!c.setup.empty()) {
    command +=
        "(" + replaced_all(replaced_all(c.setup, "@DIR@", dir), "@DELI@", DELI_BINARY) + ") && ";
  }
  command += std::string(DELI_BINARY) + " " + args;
  if (c.tmpfs) {
    // The tmpfs lives as long as the namespace: the run and its check happen inside.
    command = "unshare -m sh -c 'mount -t tmpfs -o size=1200k tmpfs " + dir + "/full && " +
              replaced_all(command, "'", "'\\''") + "; echo \"exit status $?\"; cd " + dir +
              " && (" + replaced_all(c.check.empty() ? "true" : c.check, "'", "'\\''") +
              ") > /dev/null 2>&1 && echo check passed'";
    const testing::ShellResult r = testing::run_shell(command);
    EXPECT_THAT(r.output, ::testing::HasSubstr("exit status " + std::to_string(c.status) + "\n"))
        << r.output;
    for (const std::string& m : c.messages) {
      EXPECT_THAT(r.output, ::testing::HasSubstr(replaced_all(m, "@DIR@", dir)));
    }
    if (!c.check.empty()) EXPECT_THAT(r.output, ::testing::HasSubstr("check passed"));
    return;
  }
  const testing::ShellResult r = testing::run_shell(command);
  EXPECT_EQ(r.status, c.status) << r.output;
  for (const std::string& m : c.messages) {
    EXPECT_THAT(r.output, ::testing::HasSubstr(replaced_all(m, "@DIR@", dir)));
  }
  if (c.status != 0) {
    // One line on stderr: "deli: <kind>: <message>".
    EXPECT_THAT(r.output,
                ::testing::ContainsRegex("deli: (input error|simulation stopped|error): "))
        << r.output;
  }
  if (!c.check.empty()) {
    const testing::ShellResult check =
        testing::run_shell("cd " + dir + " && " + replaced_all(c.check, "@DIR@", dir));
    EXPECT_EQ(check.status, 0) << "check failed: " << c.check << "\n" << check.output;
  }
}

INSTANTIATE_TEST_SUITE_P(Issue14, Catalogue, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace deli
