#include "input/run_input.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "forces/special_bonds.hpp"
#include "input/constraints_input.hpp"
#include "input/forcefield_input.hpp"
#include "input/integrator_input.hpp"
#include "input/output_input.hpp"
#include "input/system_input.hpp"
#include "input/thermostat_input.hpp"
#include "input/toml_table.hpp"

namespace deli {

namespace {

namespace fs = std::filesystem;

void check_box_fits_cutoff(const RunInput& input, const TomlTable& root) {
  const double cutoff = input.force_field->neighbor_cutoff();
  for (int a = 0; a < 3; ++a) {
    if (!input.system.box.periodic(a)) continue;
    const double length = input.system.box.length()[a];
    if (length < 2.0 * cutoff) {
      root.fail("the periodic box is " + std::to_string(length) + " long along " +
                std::string(1, "xyz"[a]) + ", less than twice the pair cutoff (" +
                std::to_string(cutoff) + "): make the box larger or the cutoff shorter");
    }
  }
}

// Hard spheres must not overlap even where special_bonds takes a pair out of the force
// field's neighbour list (1-3, 1-4 neighbours): those pairs are checked on their own.
void add_excluded_contacts(RunInput& input) {
  if (!input.constraints.hard_spheres) return;
  const SpecialPairs special =
      find_special_pairs(input.system.topology, input.system.particles.size());
  for (const ExcludedSpecialPair& p :
       excluded_special_pairs(special, input.force_field_spec.special_lj)) {
    if (p.separation > 1) input.constraints.always_checked_pairs.push_back({p.i, p.j});
  }
}

}  // namespace

RunInput load_run_input(const std::string& path) {
  if (fs::is_directory(path)) {
    throw InputError(path + ": is a directory, not an input file; give the TOML input inside it");
  }
  std::ifstream file(path);
  if (!file) throw InputError(path + ": cannot read the input file (does it exist?)");
  std::stringstream text;
  text << file.rdbuf();
  return parse_run_input(text.str(), path);
}

RunInput parse_run_input(const std::string& text, const std::string& path) {
  toml::table doc;
  try {
    doc = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw InputError(
        located(path, static_cast<long>(e.source().begin.line), std::string(e.description())));
  }
  RunInput input;
  input.path = path;
  input.source_text = text;
  TomlTable root(doc, path, "");
  const fs::path dir = fs::path(path).parent_path();

  auto system = root.table("system");
  if (!system) root.fail("missing the [system] table");
  DataCoefficients data_coefficients;
  input.system = read_system(*system, dir, data_coefficients);
  input.data_file = data_coefficients.file;
  system->finish();
  input.start_temperature = read_velocities(root, input.system);
  check_system_is_finite(input.system, root);
  bool rigid_bonds = false;
  input.constraints = read_constraints(root.table("constraints"), input.system, rigid_bonds);
  input.force_field_spec =
      read_force_field(root, input.system, rigid_bonds, data_coefficients, input.notes);
  input.force_field = build_force_field(input.force_field_spec, input.system);

  // Cache order wherever a pair loop runs, as LAMMPS sorts its atoms unless told not to: on
  // the AVX2 machine of stop 45 it took LJ 32000 (fcc order) to 0.85x the loop time on one
  // thread and 0.89x on two, LJ 4000 to 0.92-0.96x, the rigid melt to 0.97x, the default input
  // to 0.95-1.02x (noise); a liquid's indices scramble within thousands of steps, and then it
  // pays more (LJ 32000 shuffled: 0.47x). Without a pair loop it only costs the list's copy
  // by particle for the hard-sphere searches (1.02-1.04x).
  input.force_field->cell_order = input.force_field->neighbor_cutoff() > 0;
  if (auto n = root.table("neighbor")) {
    input.skin = n->number("skin", 0.3);
    if (input.skin < 0) n->fail("must not be negative", "skin");
    input.force_field->cell_order = n->boolean("cell_order", input.force_field->cell_order);
    input.sort_every = n->integer("sort_every", input.sort_every);
    if (input.sort_every < 0) n->fail("must not be negative (0: never sort)", "sort_every");
    n->finish();
  }
  if (auto m = root.table("minimize")) {
    input.minimize.max_steps = m->integer("max_steps");
    if (input.minimize.max_steps < 0) m->fail("must not be negative", "max_steps");
    input.minimize.timestep = positive(*m, "timestep", 0.002);
    input.minimize.max_displacement = positive(*m, "max_displacement", 0.05);
    input.minimize.force_tolerance = positive(*m, "force_tolerance", 1e-3);
    m->finish();
  }
  read_integrator(root, input);

  auto run = root.table("run");
  if (!run) root.fail("missing the [run] table (steps = ...)");
  input.steps = run->integer("steps");
  if (input.steps < 0) run->fail("must not be negative", "steps");
  if (run->has("threads")) {
    const std::int64_t threads = run->integer("threads");
    if (threads < 1 || threads > 4096) run->fail("must be from 1 to 4096", "threads");
    input.threads = static_cast<int>(threads);
  }
  input.split_small_loops = run->boolean("split_small_loops", true);
  input.balance_threads = run->boolean("balance_threads", true);
  run->finish();

  const std::vector<OutputFile> output_files = read_output(root, input);
  input.thermostat = read_thermostat(root.table("thermostat"));
  root.finish();
  std::vector<std::pair<std::string, std::string>> inputs{{"input file", path}};
  if (!input.data_file.empty()) inputs.emplace_back("data file", input.data_file);
  check_output_paths(output_files, inputs);
  check_box_fits_cutoff(input, root);
  input.degrees_of_freedom = run_degrees_of_freedom(input.system, input.constraints,
                                                    input.force_field_spec, input.thermostat);
  // Key order and formatting are toml++'s own, so comments and layout do not count.
  std::ostringstream model;
  for (const char* table : {"forcefield", "constraints"}) {
    if (const toml::table* t = doc[table].as_table()) model << "[" << table << "]\n" << *t << "\n";
  }
  input.model_text = model.str();
  input.gvi.timestep = input.timestep;
  input.gvi.skin = input.skin;
  add_excluded_contacts(input);
  return input;
}

void restore_run_input(RunInput& input, const Checkpoint& checkpoint, const std::string& path,
                       std::optional<std::uint64_t> fingerprint) {
  if (std::optional<ParticleOrder> order = order_of_ids(checkpoint.id, input.system.particles)) {
    reorder_run_input(input, *order);
  }
  apply_checkpoint(checkpoint, input.system, path, fingerprint);
}

void reorder_run_input(RunInput& input, const ParticleOrder& order) {
  reorder(input.system, order);
  input.constraints.renumber(inverse(order));
  const bool cell_order = input.force_field->cell_order;
  input.force_field = build_force_field(input.force_field_spec, input.system);
  input.force_field->cell_order = cell_order;
}

}  // namespace deli
