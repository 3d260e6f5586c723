#include "cli/commands.hpp"
#include "core/error.hpp"

namespace deli {

// Configured with -DDELI_CROSSCHECK=OFF: no OpenMM or LAMMPS to compare with.
int command_validate(const std::vector<std::string>& /*args*/) {
  throw InputError(
      "deli validate: this deli was built without OpenMM and LAMMPS (-DDELI_CROSSCHECK=OFF); "
      "reconfigure with -DDELI_CROSSCHECK=ON (setup.sh installs both) and rebuild to compare "
      "with them");
}

}  // namespace deli
