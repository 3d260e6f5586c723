#include "input/integrator_input.hpp"

namespace deli {

void read_integrator(TomlTable& root, RunInput& input) {
  auto integrator = root.table("integrator");
  if (!integrator) root.fail("missing the [integrator] table (type = \"verlet\", timestep = ...)");
  input.integrator = integrator->choice(
      "type", {"verlet", "gvi", "dsi", "midpoint", "direct", "collision"}, "verlet");
  const bool constrained = input.integrator == "gvi" || input.integrator == "dsi";
  if (input.integrator == "direct") {
    const std::string scheme =
        integrator->choice("scheme", {"midpoint", "newmark", "kane_imex"}, "midpoint");
    input.direct.scheme = scheme == "midpoint"  ? DirectScheme::midpoint
                          : scheme == "newmark" ? DirectScheme::newmark
                                                : DirectScheme::kane_imex;
    if (input.direct.scheme == DirectScheme::midpoint) {
      input.direct.alpha =
          integrator->choice("constraint_point", {"midpoint", "endpoint"}, "endpoint") == "midpoint"
              ? 0.5
              : 1.0;
    } else {
      input.direct.beta = integrator->number("beta", 0.25);
      input.direct.gamma = integrator->number("gamma", 0.5);
      if (!(input.direct.beta >= 0 && input.direct.beta <= 0.5)) {
        integrator->fail("Newmark's beta lies in [0, 1/2]", "beta");
      }
      if (!(input.direct.gamma >= 0 && input.direct.gamma <= 1)) {
        integrator->fail("Newmark's gamma lies in [0, 1]", "gamma");
      }
      if (input.direct.scheme == DirectScheme::newmark && input.direct.beta == 0) {
        integrator->fail(
            "direct Newmark with beta = 0 puts no constraint force at the step's end and "
            "cannot keep a constraint: use beta > 0 or scheme = \"kane_imex\"",
            "beta");
      }
    }
  } else if (input.integrator == "collision") {
    input.collision.base =
        integrator->choice("lagrangian", {"verlet", "midpoint"}, "verlet") == "midpoint"
            ? Lagrangian::midpoint
            : Lagrangian::verlet;
    input.collision.root_tolerance = positive(*integrator, "root_tolerance", 1e-12);
    input.collision.max_events_per_step =
        static_cast<int>(integrator->integer("max_events_per_step", 1000));
    if (input.collision.max_events_per_step < 1) {
      integrator->fail("must be at least 1", "max_events_per_step");
    }
    if (auto r = integrator->table("reflection")) {
      input.collision.energy =
          r->choice("energy", {"hamiltonian", "shadow"}, "hamiltonian") == "shadow"
              ? ReflectionEnergy::shadow
              : ReflectionEnergy::hamiltonian;
      if (input.collision.energy == ReflectionEnergy::shadow &&
          input.collision.base != Lagrangian::verlet) {
        r->fail(
            "the shadow Hamiltonian is Verlet's: use lagrangian = \"verlet\" or "
            "energy = \"hamiltonian\"",
            "energy");
      }
      r->finish();
    }
  } else if (constrained) {
    input.gvi.reflections = input.integrator == "gvi";
    if (input.gvi.reflections) {
      input.gvi.contact =
          integrator->choice("contact", {"paper", "impact_time"}, "paper") == "impact_time"
              ? ContactTreatment::impact_time
              : ContactTreatment::paper;
      if (integrator->has("shadow_remainder_steps")) {
        if (input.gvi.contact != ContactTreatment::impact_time) {
          integrator->fail("belongs to contact = \"impact_time\"", "shadow_remainder_steps");
        }
        const std::int64_t steps = integrator->integer("shadow_remainder_steps", 0);
        if (steps < 0 || steps > 1000) {
          integrator->fail("must be 0 (off) to 1000", "shadow_remainder_steps");
        }
        input.gvi.shadow_remainder_steps = static_cast<int>(steps);
      }
      // The impact-time step reflects at contact itself: the paper's options have no say.
      for (const char* key : {"predictor", "feasibility", "reflection"}) {
        if (input.gvi.contact == ContactTreatment::impact_time && integrator->has(key)) {
          integrator->fail(
              "has no meaning with contact = \"impact_time\" (every contact is reflected "
              "elastically at the instant it closes): remove it or use contact = \"paper\"",
              key);
        }
      }
    }
    input.gvi.lagrangian =
        integrator->choice("lagrangian", {"verlet", "midpoint"}, "verlet") == "midpoint"
            ? Lagrangian::midpoint
            : Lagrangian::verlet;
    input.gvi.constrained_predictor =
        integrator->choice("predictor", {"free", "constrained"}, "free") == "constrained";
    const std::string guard =
        integrator->choice("feasibility", {"restore", "reflect", "inelastic", "none"}, "restore");
    input.gvi.feasibility = guard == "restore"     ? Feasibility::restore
                            : guard == "reflect"   ? Feasibility::reflect
                            : guard == "inelastic" ? Feasibility::inelastic
                                                   : Feasibility::none;
    if (auto r = integrator->table("reflection")) {
      input.gvi.reflection =
          r->choice("operator", {"generalized", "moreau"}, "generalized") == "moreau"
              ? ReflectionOperator::moreau
              : ReflectionOperator::generalized;
      input.gvi.energy = r->choice("energy", {"hamiltonian", "shadow"}, "hamiltonian") == "shadow"
                             ? ReflectionEnergy::shadow
                             : ReflectionEnergy::hamiltonian;
      if (input.gvi.energy == ReflectionEnergy::shadow && input.force_field_spec.angle) {
        r->fail("shadow-Hamiltonian reflections need the potential's pairwise Hessian, which " +
                    input.force_field_spec.angle->style->name +
                    " angles lack: use energy = \"hamiltonian\"",
                "energy");
      }
      if (input.gvi.energy == ReflectionEnergy::shadow && input.force_field_spec.dihedral) {
        r->fail("shadow-Hamiltonian reflections need the potential's pairwise Hessian, which " +
                    input.force_field_spec.dihedral->style->name +
                    " dihedrals lack: use energy = \"hamiltonian\"",
                "energy");
      }
      if (input.gvi.energy == ReflectionEnergy::shadow &&
          input.gvi.lagrangian != Lagrangian::verlet) {
        r->fail(
            "the shadow Hamiltonian is Verlet's: use lagrangian = \"verlet\" or "
            "energy = \"hamiltonian\"",
            "energy");
      }
      r->finish();
    }
  } else if (!input.constraints.empty()) {
    integrator->fail(
        "the input has [constraints]: they need type = \"gvi\" (or \"dsi\", or the "
        "baselines \"direct\" and \"collision\")",
        "type");
  } else if (input.integrator == "midpoint") {
    input.gvi.lagrangian = Lagrangian::midpoint;  // implicit midpoint, nothing to constrain
  }
  input.timestep = positive(*integrator, "timestep");
  integrator->finish();
}

}  // namespace deli
