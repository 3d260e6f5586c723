#include "input/output_input.hpp"

namespace deli {

std::vector<OutputFile> read_output(TomlTable& root, RunInput& input) {
  std::vector<OutputFile> output_files;
  if (auto output = root.table("output")) {
    if (auto thermo = output->table("thermo")) {
      input.thermo.every = thermo->integer("every", 100);
      if (input.thermo.every < 0) thermo->fail("must not be negative", "every");
      input.thermo.file = thermo->string("file", "");
      output_files.push_back({"thermo", input.thermo.file, *thermo});
      thermo->finish();
    }
    if (auto checkpoint = output->table("checkpoint")) {
      input.checkpoint.file = checkpoint->string("file");
      output_files.push_back({"checkpoint", input.checkpoint.file, *checkpoint});
      input.checkpoint.every = checkpoint->integer("every", 10000);
      if (input.checkpoint.every < 1) checkpoint->fail("must be at least 1", "every");
      checkpoint->finish();
    }
    if (auto dump = output->table("dump")) {
      input.dump.file = dump->string("file");
      output_files.push_back({"dump", input.dump.file, *dump});
      input.dump.format = dump->choice("format", {"lammps", "xyz"}, "lammps");
      // Extended XYZ names type k by the element of atomic number k (ASE reads no others).
      if (input.dump.format == "xyz" && input.system.atom_types.size() > 118) {
        dump->fail("names atom types by element symbols, 118 at most; this system has " +
                       std::to_string(input.system.atom_types.size()) +
                       " types: use format = \"lammps\"",
                   "format");
      }
      input.dump.every = dump->integer("every", 1000);
      if (input.dump.every < 1) dump->fail("must be at least 1", "every");
      dump->finish();
    }
    if (auto trajectory = output->table("trajectory")) {
      input.trajectory.file = trajectory->string("file");
      output_files.push_back({"trajectory", input.trajectory.file, *trajectory});
      input.trajectory.every = trajectory->integer("every", 1000);
      if (input.trajectory.every < 1) trajectory->fail("must be at least 1", "every");
      input.trajectory.velocities = trajectory->boolean("velocities", true);
      input.trajectory.images = trajectory->boolean("images", true);
      input.trajectory.forces = trajectory->boolean("forces", false);
      input.trajectory.compression = static_cast<int>(trajectory->integer("compression", 4));
      if (input.trajectory.compression < 0 || input.trajectory.compression > 9) {
        trajectory->fail("deflate level from 0 (none) to 9", "compression");
      }
      trajectory->finish();
    }
    input.final_data = output->string("final_data", "");
    output_files.push_back({"final data", input.final_data, *output, "final_data"});
    input.log = output->string("log", "");
    output_files.push_back({"log", input.log, *output, "log"});
    output->finish();
  }
  return output_files;
}

}  // namespace deli
