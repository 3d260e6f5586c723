// A deli H5MD trajectory read back as a user would (h5py, MDAnalysis) equals what deli
// held, frame by frame.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "h5md/h5md_writer.hpp"
#include "input/lammps_data.hpp"
#include "input/run_input.hpp"
#include "integrators/velocity_verlet.hpp"
#include "simulation/run_loop.hpp"
#include "support/file_contents.hpp"
#include "support/process_temp_dir.hpp"
#include "support/shell.hpp"
#include "text/dump_writer.hpp"

namespace deli {
namespace {

// Writes what deli holds at each frame, at 17 digits (a bit-exact round trip).
class Expected final : public Observer {
 public:
  Expected(const std::string& path, std::int64_t every) : out_(path), every_(every) {
    out_.precision(17);
  }
  bool wants_frame(std::int64_t step) const override { return step % every_ == 0; }
  void on_frame(const System& s, const ThermoSample&, const std::vector<Vec3>& forces) override {
    const Vec3 l = s.box.length();
    out_ << s.particles.size() << ' ' << s.step << ' ' << s.time << ' ' << l.x << ' ' << l.y << ' '
         << l.z << '\n';
    for (std::size_t i = 0; i < s.particles.size(); ++i) {
      const Vec3& x = s.particles.position[i];
      const Vec3& v = s.particles.velocity[i];
      const Vec3& f = forces[i];
      out_ << x.x << ' ' << x.y << ' ' << x.z << ' ' << v.x << ' ' << v.y << ' ' << v.z << ' '
           << f.x << ' ' << f.y << ' ' << f.z << '\n';
    }
    out_.flush();
  }

 private:
  std::ofstream out_;
  std::int64_t every_;
};

TEST(H5md, MDAnalysisAndH5pyReadWhatDeliHeld) {
  const std::string dir = deli::testing::process_temp_dir();
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  write_lammps_data(input.system, dir + "/melt.data", "bond", "h5md test");
  H5mdWriter writer({dir + "/melt.h5", 25, true, true, 4, true}, input.system, input.source_text,
                    "test");
  Expected expected(dir + "/expected.txt", 25);
  VelocityVerlet verlet(*input.force_field, input.skin, input.timestep);
  run(input.system, verlet, 100, 50, {&writer, &expected});
  EXPECT_EQ(writer.frames(), 5);
  const std::string command = "/usr/bin/python3 " + std::string(DELI_SOURCE_DIR) +
                              "/tests/io/h5md_roundtrip.py " + dir + "/melt.h5 " + dir +
                              "/expected.txt " + dir + "/melt.data";
  const testing::ShellResult r = testing::run_shell(command);
  std::printf("%s", r.output.c_str());
  EXPECT_EQ(r.status, 0) << r.output;
}

// Series sampled at every frame share the position's step and time, extended once per
// frame; an observable that first appears at a later frame keeps a step and time of its
// own. A continuation cuts both back and extends them again.
TEST(H5md, SharedAndOwnStepAndTimeAcrossAContinuation) {
  const std::string dir = deli::testing::process_temp_dir();
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  System& system = input.system;
  const std::vector<Vec3> forces(system.particles.size());
  const TrajectorySpec spec{dir + "/late.h5", 10, true, true, 0, false};
  auto write = [&](H5mdWriter& writer, std::int64_t from, std::int64_t to) {
    for (std::int64_t step = from; step <= to; step += 10) {
      system.step = step;
      system.time = 0.005 * static_cast<double>(step);
      ThermoSample sample;
      if (step >= 20) sample.integrator = {{"late", static_cast<double>(step)}};
      writer.on_frame(system, sample, forces);
    }
    writer.on_finish(system);
  };
  {
    H5mdWriter writer(spec, system, input.source_text, "t");
    write(writer, 0, 40);
  }
  {
    H5mdWriter writer(spec, system, input.source_text, "t", {}, false,
                      TrajectoryContinuation{25});  // frames 30 and 40 cut, then again
    write(writer, 30, 50);
  }
  testing::ShellResult r =
      testing::run_shell("/usr/bin/python3 " + std::string(DELI_SOURCE_DIR) +
                         "/tests/io/h5md_conformance.py --deli " + dir + "/late.h5");
  EXPECT_EQ(r.status, 0) << r.output;
  r = testing::run_shell("/usr/bin/python3 -c \"import h5py; f = h5py.File('" + dir +
                         "/late.h5'); a = f['particles/all']; o = f['observables']; "
                         "print(a['position/step'][:].tolist(), o['late/step'][:].tolist(), "
                         "o['late/value'][:].tolist(), o['late/step'] == a['position/step'], "
                         "o['temperature/time'] == a['position/time'], "
                         "a['box/edges/value'].shape[0])\"");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("[0, 10, 20, 30, 40, 50] [20, 30, 40, 50] [20.0, 30.0, 40.0, 50.0] "
                          "False True 6"),
            std::string::npos)
      << r.output;
}

// The plot tool turns the same kind of file into a PNG.
TEST(H5md, PlotToolWritesAPng) {
  const std::string dir = deli::testing::process_temp_dir();
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  H5mdWriter writer({dir + "/plot.h5", 10, false, false, 0}, input.system, input.source_text, "t");
  VelocityVerlet verlet(*input.force_field, input.skin, input.timestep);
  run(input.system, verlet, 30, 30, {&writer});
  writer.on_finish(input.system);
  const std::string command = "/usr/bin/python3 " + std::string(DELI_SOURCE_DIR) +
                              "/tools/plot_h5md.py " + dir + "/plot.h5 " + dir + "/plot.png 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0);
  std::ifstream png(dir + "/plot.png", std::ios::binary);
  char signature[8] = {};
  png.read(signature, 8);
  EXPECT_EQ(std::string(signature + 1, 3), "PNG");
}

// `deli info` on the same kind of file names what is in it.
TEST(H5md, InfoSummarisesTheFile) {
  const std::string dir = deli::testing::process_temp_dir();
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  H5mdWriter writer({dir + "/info.h5", 10, true, false, 0}, input.system, input.source_text, "t");
  VelocityVerlet verlet(*input.force_field, input.skin, input.timestep);
  run(input.system, verlet, 30, 30, {&writer});
  writer.on_finish(input.system);
  const auto [status, output] =
      testing::run_shell(std::string(DELI_BINARY) + " info " + dir + "/info.h5");
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("4000 atoms, 4 frames, time 0 to 0.15"), std::string::npos) << output;
  EXPECT_NE(output.find("bonds: 3800"), std::string::npos) << output;
  EXPECT_EQ(output.find("image"), std::string::npos) << "images were not asked for";
}

// An input of the repository with its data file made absolute, run for `steps` steps with
// an H5MD trajectory (forces too) every 10 steps and an XYZ dump every 20.
std::string short_run(const std::string& source, const std::string& dir, int steps) {
  std::string text = testing::file_contents(std::string(DELI_SOURCE_DIR) + "/" + source);
  text = text.substr(0, text.find("[run]"));
  const std::string source_dir =
      std::string(DELI_SOURCE_DIR) + "/" + source.substr(0, source.rfind('/') + 1);
  const auto data = text.find("data = \"");
  if (data != std::string::npos) text.insert(data + 8, source_dir);
  const std::string path = dir + "/run.toml";
  std::ofstream(path) << text << "[run]\nsteps = " << steps << "\n[output]\n"
                      << "trajectory = { file = \"" << dir
                      << "/out.h5\", every = 10, forces = true }\n"
                      << "dump = { file = \"" << dir
                      << "/out.xyz\", every = 20, format = \"xyz\" }\n";
  return path;
}

// `deli run` writes what H5MD 1.1 requires (tests/io/h5md_conformance.py walks the file):
// a GVI run with rods, hard spheres and walls, and a plain LJ liquid. Connectivity holds
// particle ids, the hard-sphere diameters are stored, series share the position's step and
// time; the XYZ dump is extended XYZ with the box.
struct ConformanceCase {
  std::string input;
  std::string rods_and_diameter;  // what the h5py summary prints
  std::string xyz_frame;          // the XYZ checker's line for frame 1
};
class Conformance : public ::testing::TestWithParam<ConformanceCase> {};

TEST_P(Conformance, DeliRunWritesH5md11AndExtendedXyz) {
  const ConformanceCase& c = GetParam();
  std::string name = c.input.substr(c.input.rfind('/') + 1);
  const std::string dir =
      deli::testing::process_temp_dir() + "/conformance_" + name.substr(0, name.find('.'));
  ASSERT_EQ(testing::run_shell("rm -rf " + dir + " && mkdir -p " + dir).status, 0);
  testing::ShellResult r =
      testing::run_shell(std::string(DELI_BINARY) + " run " + short_run(c.input, dir, 40));
  ASSERT_EQ(r.status, 0) << r.output;
  r = testing::run_shell("/usr/bin/python3 " + std::string(DELI_SOURCE_DIR) +
                         "/tests/io/h5md_conformance.py --deli " + dir + "/out.h5");
  std::printf("%s", r.output.c_str());
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("H5MD 1.1 conformant"), std::string::npos) << r.output;
  // The rods as pairs of the data file's atom ids; the diameters of the hard spheres.
  r = testing::run_shell("/usr/bin/python3 -c \"import h5py, numpy as np; f = h5py.File('" + dir +
                         "/out.h5'); a = f['particles/all']; c = f.get('connectivity/rods'); "
                         "print('rods', 0 if c is None else c.shape[0], c is None or "
                         "bool(np.isin(c[:], a['id'][:]).all() and c[:].min() >= 1), 'diameter', "
                         "sorted(set(a['diameter'][:])) if 'diameter' in a else None, "
                         "a['velocity/step'] == a['position/step'] or 'copies')\"");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(c.rods_and_diameter), std::string::npos) << r.output;
  r = testing::run_shell("/usr/bin/python3 " + std::string(DELI_SOURCE_DIR) +
                         "/tests/io/extxyz_check.py " + dir + "/out.xyz");
  std::printf("%s", r.output.c_str());
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.xyz_frame), std::string::npos) << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    Runs, Conformance,
    ::testing::Values(
        ConformanceCase{"inputs/lj_chains/rigid_slit.toml", "rods 1140 True diameter [0.95] True",
                        "frame 1 step 20 time 0.08 atoms 1200 lattice 12.97 12.97 12.97 "
                        "pbc TTF origin 0 0 0 columns species:S:1:pos:R:3:id:I:1:radius:R:1"},
        ConformanceCase{"inputs/lj_liquid/lj_4000.toml", "rods 0 True diameter None True",
                        "frame 1 step 20 time 0.1 atoms 4000 lattice 16.796 16.796 16.796 "
                        "pbc TTT origin 0 0 0 columns species:S:1:pos:R:3:id:I:1 first H "}),
    [](const ::testing::TestParamInfo<ConformanceCase>& info) {
      const std::string file = info.param.input.substr(info.param.input.rfind('/') + 1);
      return file.substr(0, file.find('.'));
    });

}  // namespace
}  // namespace deli

namespace deli {
namespace {

// The LAMMPS dump layout, read back: frames, atom count, and coordinates to the 10 digits
// written.
TEST(Dump, LammpsCustomLayoutReadsBack) {
  const std::string dir = deli::testing::process_temp_dir();
  RunInput input = load_run_input(std::string(DELI_SOURCE_DIR) + "/inputs/lj_chains/melt.toml");
  DumpWriter dump(dir + "/melt.lammpstrj", DumpWriter::Format::lammps, 20);
  VelocityVerlet verlet(*input.force_field, input.skin, input.timestep);
  run(input.system, verlet, 40, 40, {&dump});
  std::ifstream in(dir + "/melt.lammpstrj");
  std::string line;
  int frames = 0;
  double x_of_atom_1 = 0;
  while (std::getline(in, line)) {
    if (line == "ITEM: TIMESTEP") ++frames;
    if (line.rfind("ITEM: ATOMS id type x y z", 0) == 0) {
      std::getline(in, line);
      std::istringstream fields(line);
      long id;
      int type;
      fields >> id >> type >> x_of_atom_1;
      EXPECT_EQ(id, 1);
    }
  }
  EXPECT_EQ(frames, 3);
  EXPECT_NEAR(x_of_atom_1, input.system.particles.position[0].x,
              1e-9 * std::abs(input.system.particles.position[0].x));
}

}  // namespace
}  // namespace deli
