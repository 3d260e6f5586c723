#include "text/dump_writer.hpp"

#include <array>

#include "core/error.hpp"
#include "system/particle_order.hpp"
#include "text/continuation.hpp"
#include "text/write_failure.hpp"

namespace deli {

namespace {

// Extended XYZ species are chemical symbols for ASE (it builds Atoms from them) and names
// for OVITO: type k is the element of atomic number k, as ASE's LAMMPS readers map types,
// so that `atoms.numbers` gives the type numbers back.
const std::array<const char*, 118> elements{
    "H",  "He", "Li", "Be", "B",  "C",  "N",  "O",  "F",  "Ne", "Na", "Mg", "Al", "Si", "P",
    "S",  "Cl", "Ar", "K",  "Ca", "Sc", "Ti", "V",  "Cr", "Mn", "Fe", "Co", "Ni", "Cu", "Zn",
    "Ga", "Ge", "As", "Se", "Br", "Kr", "Rb", "Sr", "Y",  "Zr", "Nb", "Mo", "Tc", "Ru", "Rh",
    "Pd", "Ag", "Cd", "In", "Sn", "Sb", "Te", "I",  "Xe", "Cs", "Ba", "La", "Ce", "Pr", "Nd",
    "Pm", "Sm", "Eu", "Gd", "Tb", "Dy", "Ho", "Er", "Tm", "Yb", "Lu", "Hf", "Ta", "W",  "Re",
    "Os", "Ir", "Pt", "Au", "Hg", "Tl", "Pb", "Bi", "Po", "At", "Rn", "Fr", "Ra", "Ac", "Th",
    "Pa", "U",  "Np", "Pu", "Am", "Cm", "Bk", "Cf", "Es", "Fm", "Md", "No", "Lr", "Rf", "Db",
    "Sg", "Bh", "Hs", "Mt", "Ds", "Rg", "Cn", "Nh", "Fl", "Mc", "Lv", "Ts", "Og"};

}  // namespace

const char* xyz_species(int type) {
  if (type < 0 || type >= static_cast<int>(elements.size())) {
    throw InputError("the XYZ dump names atom types 1 to 118 as elements; type " +
                     std::to_string(type + 1) + " has no name: use format = \"lammps\"");
  }
  return elements[static_cast<std::size_t>(type)];
}

DumpWriter::DumpWriter(const std::string& path, Format format, std::int64_t every,
                       std::int64_t continue_from, bool hard_spheres)
    : path_(path), format_(format), every_(every), radii_(hard_spheres) {
  bool kept = false;
  if (continue_from >= 0) {
    // LAMMPS: "ITEM: TIMESTEP" then the step; XYZ: the atom count, then the comment line
    // with "Step=N".
    kept = cut_back_after_step(path, continue_from,
                               [format](const std::vector<std::string>& lines,
                                        std::size_t k) -> std::optional<std::int64_t> {
                                 if (k + 1 >= lines.size()) return std::nullopt;
                                 if (format == Format::lammps) {
                                   if (lines[k] != "ITEM: TIMESTEP") return std::nullopt;
                                   return std::stoll(lines[k + 1]);
                                 }
                                 const std::size_t at = lines[k + 1].find(" Step=");
                                 if (lines[k + 1].rfind("Lattice=", 0) != 0 ||
                                     at == std::string::npos ||
                                     lines[k].find(' ') != std::string::npos) {
                                   return std::nullopt;
                                 }
                                 return std::stoll(lines[k + 1].substr(at + 6));
                               });
  }
  out_.open(path, kept ? std::ios::app : std::ios::trunc);
  if (!out_) {
    throw InputError(path +
                     ": cannot open the dump file for writing; check that the directory "
                     "exists and is writable");
  }
  written_ = bytes_in_file(path);
  out_.precision(10);
}

void DumpWriter::on_frame(const System& system, const ThermoSample&, const std::vector<Vec3>&) {
  const Particles& p = system.particles;
  const Box& box = system.box;
  // Lines in the input's order, whatever order the run has put the particles in.
  const ParticleOrder listed = p.origin.empty() ? ParticleOrder{} : inverse(p.origin);
  auto index_of_line = [&](std::size_t line) {
    return listed.empty() ? line : static_cast<std::size_t>(listed[line]);
  };
  if (format_ == Format::xyz) {
    // Extended XYZ (ASE, OVITO): the cell's edge vectors as rows (Lattice), its corner
    // (Origin, OVITO's key), the periodic axes (pbc), then species, position, id, and the
    // hard-sphere radius where particles have one.
    const Vec3 l = box.length();
    const Vec3 lo = box.lo();
    const bool radii = radii_;
    out_ << p.size() << "\nLattice=\"" << l.x << " 0 0 0 " << l.y << " 0 0 0 " << l.z
         << "\" Origin=\"" << lo.x << ' ' << lo.y << ' ' << lo.z
         << "\" Properties=species:S:1:pos:R:3:id:I:1" << (radii ? ":radius:R:1" : "") << " pbc=\""
         << (box.periodic(0) ? 'T' : 'F') << ' ' << (box.periodic(1) ? 'T' : 'F') << ' '
         << (box.periodic(2) ? 'T' : 'F') << "\" Time=" << system.time << " Step=" << system.step
         << '\n';
    for (std::size_t line = 0; line < p.size(); ++line) {
      const std::size_t i = index_of_line(line);
      out_ << xyz_species(p.type[i]) << ' ' << p.position[i].x << ' ' << p.position[i].y << ' '
           << p.position[i].z << ' ' << p.id[i];
      if (radii) out_ << ' ' << p.radius[i];
      out_ << '\n';
    }
  } else {
    out_ << "ITEM: TIMESTEP\n"
         << system.step << "\nITEM: NUMBER OF ATOMS\n"
         << p.size() << "\nITEM: BOX BOUNDS " << (box.periodic(0) ? "pp" : "ff") << ' '
         << (box.periodic(1) ? "pp" : "ff") << ' ' << (box.periodic(2) ? "pp" : "ff") << '\n';
    for (int a = 0; a < 3; ++a) out_ << box.lo()[a] << ' ' << box.hi()[a] << '\n';
    out_ << "ITEM: ATOMS id type x y z ix iy iz vx vy vz\n";
    for (std::size_t line = 0; line < p.size(); ++line) {
      const std::size_t i = index_of_line(line);
      const Vec3& x = p.position[i];
      const Vec3& v = p.velocity[i];
      out_ << p.id[i] << ' ' << p.type[i] + 1 << ' ' << x.x << ' ' << x.y << ' ' << x.z << ' '
           << p.image[i][0] << ' ' << p.image[i][1] << ' ' << p.image[i][2] << ' ' << v.x << ' '
           << v.y << ' ' << v.z << '\n';
    }
  }
  out_.flush();
  if (!out_) {
    drop_partial_record(out_, path_, written_);
    throw SimulationError(path_ + ": could not write the frame of step " +
                          std::to_string(system.step) +
                          " (disk full or not writable?); the frames before it are kept");
  }
  written_ = bytes_in_file(path_);
}

void DumpWriter::on_finish(const System&) {
  if (!out_.is_open()) return;
  out_.close();
  if (!out_) throw SimulationError(path_ + ": could not close the dump file (disk full?)");
}

}  // namespace deli
