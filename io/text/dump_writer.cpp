#include "text/dump_writer.hpp"

#include "core/error.hpp"
#include "text/continuation.hpp"
#include "text/write_failure.hpp"

namespace deli {

DumpWriter::DumpWriter(const std::string& path, Format format, std::int64_t every,
                       std::int64_t continue_from)
    : path_(path), format_(format), every_(every) {
  bool kept = false;
  if (continue_from >= 0) {
    // LAMMPS: "ITEM: TIMESTEP" then the step; XYZ: the atom count, then "step N ...".
    kept = cut_back_after_step(
        path, continue_from,
        [format](const std::vector<std::string>& lines,
                 std::size_t k) -> std::optional<std::int64_t> {
          if (k + 1 >= lines.size()) return std::nullopt;
          if (format == Format::lammps) {
            if (lines[k] != "ITEM: TIMESTEP") return std::nullopt;
            return std::stoll(lines[k + 1]);
          }
          if (lines[k + 1].rfind("step ", 0) != 0 || lines[k].find(' ') != std::string::npos) {
            return std::nullopt;
          }
          return std::stoll(lines[k + 1].substr(5));
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
  if (format_ == Format::xyz) {
    out_ << p.size() << "\nstep " << system.step << " time " << system.time << " box "
         << box.length().x << ' ' << box.length().y << ' ' << box.length().z << '\n';
    for (std::size_t i = 0; i < p.size(); ++i) {
      out_ << p.type[i] + 1 << ' ' << p.position[i].x << ' ' << p.position[i].y << ' '
           << p.position[i].z << '\n';
    }
  } else {
    out_ << "ITEM: TIMESTEP\n"
         << system.step << "\nITEM: NUMBER OF ATOMS\n"
         << p.size() << "\nITEM: BOX BOUNDS " << (box.periodic(0) ? "pp" : "ff") << ' '
         << (box.periodic(1) ? "pp" : "ff") << ' ' << (box.periodic(2) ? "pp" : "ff") << '\n';
    for (int a = 0; a < 3; ++a) out_ << box.lo()[a] << ' ' << box.hi()[a] << '\n';
    out_ << "ITEM: ATOMS id type x y z ix iy iz vx vy vz\n";
    for (std::size_t i = 0; i < p.size(); ++i) {
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
