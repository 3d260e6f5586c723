#pragma once

#include <fstream>
#include <string>
#include <vector>

#include "input/run_input.hpp"
#include "support/process_temp_dir.hpp"

namespace deli::testing {

struct Atom {
  Vec3 x, v;
  int type = 1;
  double mass = 1.0;
};

// An input whose system is `atoms` in the box [lo, hi] (through a LAMMPS data file in the
// test's temporary directory), followed by the TOML `rest` (force field, constraints...).
inline RunInput input_with_atoms(const std::string& name, const std::vector<Atom>& atoms,
                                 const std::string& boundary, Vec3 lo, Vec3 hi,
                                 const std::string& rest) {
  const std::string dir = deli::testing::process_temp_dir();
  int types = 1;
  for (const Atom& a : atoms) types = std::max(types, a.type);
  {
    std::ofstream data(dir + "/" + name + ".data");
    data.precision(17);
    data << name << "\n\n" << atoms.size() << " atoms\n" << types << " atom types\n\n";
    data << lo.x << " " << hi.x << " xlo xhi\n"
         << lo.y << " " << hi.y << " ylo yhi\n"
         << lo.z << " " << hi.z << " zlo zhi\n\nMasses\n\n";
    for (int t = 1; t <= types; ++t) {
      double m = 1.0;
      for (const Atom& a : atoms) {
        if (a.type == t) m = a.mass;
      }
      data << t << " " << m << "\n";
    }
    data << "\nAtoms # atomic\n\n";
    for (std::size_t i = 0; i < atoms.size(); ++i) {
      data << i + 1 << " " << atoms[i].type << " " << atoms[i].x.x << " " << atoms[i].x.y << " "
           << atoms[i].x.z << "\n";
    }
    data << "\nVelocities\n\n";
    for (std::size_t i = 0; i < atoms.size(); ++i) {
      data << i + 1 << " " << atoms[i].v.x << " " << atoms[i].v.y << " " << atoms[i].v.z << "\n";
    }
  }
  const std::string toml = "[system]\ndata = \"" + dir + "/" + name + ".data\"\nboundary = \"" +
                           boundary + "\"\n" + rest;
  return parse_run_input(toml, dir + "/" + name + ".toml");
}

}  // namespace deli::testing
