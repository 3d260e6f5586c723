#include "crosscheck/openmm_bridge.hpp"

#include <OpenMM.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "forces/special_bonds.hpp"

namespace deli {

namespace {

std::vector<OpenMM::Vec3> to_openmm(const std::vector<Vec3>& v) {
  std::vector<OpenMM::Vec3> out;
  out.reserve(v.size());
  for (const Vec3& x : v) out.emplace_back(x.x, x.y, x.z);
  return out;
}

std::vector<Vec3> from_openmm(const std::vector<OpenMM::Vec3>& v) {
  std::vector<Vec3> out;
  out.reserve(v.size());
  for (const OpenMM::Vec3& x : v) out.push_back({x[0], x[1], x[2]});
  return out;
}

// Force groups, one per deli term, so that each term's energy can be read alone.
constexpr int kPairGroup = 0, kBondGroup = 1, kAngleGroup = 2, kScaledPairGroup = 3,
              kExternalGroup = 4, kDihedralGroup = 5;

// k_B N_A in kJ/mol/K, exactly as OpenMM's BOLTZ (SI 2019 constants).
constexpr double kBoltzmannKJPerMolK = 1.380649e-23 * 6.02214076e23 / 1000.0;

}  // namespace

struct OpenMMBridge::Impl {
  OpenMM::System system;
  std::unique_ptr<OpenMM::Integrator> integrator;
  std::unique_ptr<OpenMM::Context> context;
  std::string platform_name;
  OpenMM::Platform* platform = nullptr;
  std::map<std::string, std::string> properties;
  bool periodic = false;
  Vec3 box_length;
  std::array<bool, 3> padded{false, false, false};  // open axes made periodic and long
  double cutoff = 0.0;
  std::vector<double> mass;
  std::vector<std::string> term_names;
  std::vector<int> term_groups;  // bitmask per term
};

OpenMMBridge::OpenMMBridge(const System& sys, const ForceFieldSpec& spec, Platform platform,
                           const std::vector<Constraint>& rods, double constraint_tolerance)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const auto& periodic = sys.box.periodic();
  m.periodic = periodic[0] || periodic[1] || periodic[2];
  m.box_length = sys.box.length();
  m.cutoff = spec.pair ? spec.pair->max_cutoff() : 0.0;
  // OpenMM boxes are periodic along all axes or none. An open axis of a partly periodic
  // box becomes a periodic one long enough that no atom meets another's image: twice the
  // atoms' extent plus twice the cutoff and 10 sigma (run_nve checks it stayed so).
  for (int a = 0; a < 3; ++a) {
    if (!m.periodic || periodic[a]) continue;
    double lo = 0.0, hi = 0.0;
    for (std::size_t i = 0; i < sys.particles.size(); ++i) {
      const double x = sys.particles.position[i][a];
      lo = i == 0 ? x : std::min(lo, x);
      hi = i == 0 ? x : std::max(hi, x);
    }
    m.padded[a] = true;
    m.box_length[a] = 2.0 * (hi - lo) + 2.0 * m.cutoff + 10.0;
  }
  if (m.periodic) {
    m.system.setDefaultPeriodicBoxVectors(OpenMM::Vec3(m.box_length.x, 0, 0),
                                          OpenMM::Vec3(0, m.box_length.y, 0),
                                          OpenMM::Vec3(0, 0, m.box_length.z));
  }
  for (double mass : sys.particles.mass) m.system.addParticle(mass);
  m.mass = sys.particles.mass;

  const SpecialPairs special = find_special_pairs(sys.topology, sys.particles.size());
  if (spec.pair) {
    const PairStyle& style = *spec.pair->style;
    if (style.openmm_energy.empty()) {
      throw UnsupportedModel("OpenMM has no pair style '" + style.name + "' here");
    }
    const PairCoefficients& c = spec.pair->coefficients;
    const int types = c.type_count();
    const std::size_t count = style.coefficients.size();
    // Per type pair: the coefficients, then the cutoff and the shift, each a table.
    std::vector<std::vector<double>> tables(count + 2);
    for (int b = 0; b < types; ++b) {
      for (int a = 0; a < types; ++a) {
        const PairCoefficient& p = c.at(a, b);
        for (std::size_t k = 0; k < count; ++k) tables[k].push_back(p.values[k]);
        tables[count].push_back(p.cutoff);
        tables[count + 1].push_back(spec.pair->shift ? style.energy(p.values, p.cutoff) : 0.0);
      }
    }
    std::vector<std::string> names;
    for (const StyleCoefficient& k : style.coefficients) names.push_back(k.name);
    names.push_back("cut");
    names.push_back("shift");
    const std::string energy = "step(cut - r)*(" + style.openmm_energy + " - shift)";
    std::string expression = energy;
    for (const std::string& n : names) expression += "; " + n + " = " + n + "T(t1, t2)";
    auto* pair = new OpenMM::CustomNonbondedForce(expression);
    pair->addPerParticleParameter("t");
    for (std::size_t k = 0; k < names.size(); ++k) {
      pair->addTabulatedFunction(names[k] + "T",
                                 new OpenMM::Discrete2DFunction(types, types, tables[k]));
    }
    pair->setNonbondedMethod(m.periodic ? OpenMM::CustomNonbondedForce::CutoffPeriodic
                                        : OpenMM::CustomNonbondedForce::CutoffNonPeriodic);
    pair->setCutoffDistance(spec.pair->max_cutoff());
    pair->setUseSwitchingFunction(false);
    pair->setUseLongRangeCorrection(false);
    for (int t : sys.particles.type) pair->addParticle({static_cast<double>(t)});
    pair->setForceGroup(kPairGroup);

    // Special pairs: excluded from the nonbonded force; scaled ones come back as bonds.
    auto* scaled = new OpenMM::CustomBondForce("f*" + energy);
    scaled->addPerBondParameter("f");
    for (const std::string& n : names) scaled->addPerBondParameter(n);
    scaled->setUsesPeriodicBoundaryConditions(m.periodic);
    scaled->setForceGroup(kScaledPairGroup);
    for (const ExcludedSpecialPair& p : excluded_special_pairs(special, spec.special_lj)) {
      pair->addExclusion(p.i, p.j);
      if (!p.scaled()) continue;
      const int ti = sys.particles.type[p.i], tj = sys.particles.type[p.j];
      const std::size_t k = static_cast<std::size_t>(ti + types * tj);
      std::vector<double> parameters{p.factor};
      for (const std::vector<double>& table : tables) parameters.push_back(table[k]);
      scaled->addBond(p.i, p.j, parameters);
    }
    m.system.addForce(pair);
    m.term_names.push_back("pair");
    m.term_groups.push_back(1 << kPairGroup | 1 << kScaledPairGroup);
    if (scaled->getNumBonds() > 0) {
      m.system.addForce(scaled);
    } else {
      delete scaled;
    }
  }
  // Bonds and angles: per style, its registered energy expression with its coefficients
  // as per-bond (per-angle) parameters, for the bonds of that style's types.
  auto checked = [](const BondedStyle& style, const char* kind) {
    if (style.openmm_energy.empty()) {
      throw UnsupportedModel(std::string("OpenMM has no ") + kind + " style '" + style.name +
                             "' here");
    }
    return style.openmm_energy;
  };
  if (spec.bond) {
    for (const BondedStyle* style : spec.bond->styles()) {
      auto* bonds = new OpenMM::CustomBondForce(checked(*style, "bond"));
      for (const StyleCoefficient& c : style->coefficients) bonds->addPerBondParameter(c.name);
      for (const Bond& b : sys.topology.bonds) {
        if (spec.bond->style_by_type[b.type] != style) continue;
        bonds->addBond(b.i, b.j, spec.bond->by_type[b.type]);
      }
      bonds->setUsesPeriodicBoundaryConditions(m.periodic);
      bonds->setForceGroup(kBondGroup);
      m.system.addForce(bonds);
    }
    m.term_names.push_back("bond");
    m.term_groups.push_back(1 << kBondGroup);
  }
  if (spec.angle) {
    for (const BondedStyle* style : spec.angle->styles()) {
      auto* angles = new OpenMM::CustomAngleForce(checked(*style, "angle"));
      for (const StyleCoefficient& c : style->coefficients) angles->addPerAngleParameter(c.name);
      for (const Angle& a : sys.topology.angles) {
        if (spec.angle->style_by_type[a.type] != style) continue;
        angles->addAngle(a.i, a.j, a.k, spec.angle->by_type[a.type]);
      }
      angles->setUsesPeriodicBoundaryConditions(m.periodic);
      angles->setForceGroup(kAngleGroup);
      m.system.addForce(angles);
    }
    m.term_names.push_back("angle");
    m.term_groups.push_back(1 << kAngleGroup);
  }
  if (spec.dihedral) {
    for (const BondedStyle* style : spec.dihedral->styles()) {
      auto* torsions = new OpenMM::CustomTorsionForce(checked(*style, "dihedral"));
      for (const StyleCoefficient& c : style->coefficients)
        torsions->addPerTorsionParameter(c.name);
      for (const Dihedral& d : sys.topology.dihedrals) {
        if (spec.dihedral->style_by_type[d.type] != style) continue;
        torsions->addTorsion(d.i, d.j, d.k, d.l, spec.dihedral->by_type[d.type]);
      }
      torsions->setUsesPeriodicBoundaryConditions(m.periodic);
      torsions->setForceGroup(kDihedralGroup);
      m.system.addForce(torsions);
    }
    m.term_names.push_back("dihedral");
    m.term_groups.push_back(1 << kDihedralGroup);
  }

  // External fields, on positions as given (deli's act on positions as stored: the two
  // agree along open axes, where the fields are meant to be used).
  int external_terms = 0;
  auto add_external = [&](OpenMM::CustomExternalForce* f) {
    f->setForceGroup(kExternalGroup);
    m.system.addForce(f);
    ++external_terms;
  };
  if (spec.gravity) {
    auto* f = new OpenMM::CustomExternalForce("-m*(gx*x + gy*y + gz*z)");
    f->addGlobalParameter("gx", spec.gravity->x);
    f->addGlobalParameter("gy", spec.gravity->y);
    f->addGlobalParameter("gz", spec.gravity->z);
    f->addPerParticleParameter("m");
    for (std::size_t i = 0; i < sys.particles.size(); ++i) {
      f->addParticle(static_cast<int>(i), {sys.particles.mass[i]});
    }
    add_external(f);
  }
  for (std::size_t r = 0; r < spec.radial.size(); ++r) {
    const ForceFieldSpec::Radial& radial = spec.radial[r];
    const std::string tag = "r" + std::to_string(r) + "_";
    std::string v;
    if (radial.inverse_square) {
      v = tag + "a0/s";
    } else {  // Horner: a0 + s*(a1 + s*(a2 + ...))
      for (std::size_t k = radial.coefficients.size(); k-- > 0;) {
        const std::string a = tag + "a" + std::to_string(k);
        v = v.empty() ? a : a + " + s*(" + v + ")";
      }
      if (v.empty()) v = "0";
    }
    auto* f = new OpenMM::CustomExternalForce(v + "; s = (x - " + tag + "cx)^2 + (y - " + tag +
                                              "cy)^2 + (z - " + tag + "cz)^2");
    f->addGlobalParameter(tag + "cx", radial.center.x);
    f->addGlobalParameter(tag + "cy", radial.center.y);
    f->addGlobalParameter(tag + "cz", radial.center.z);
    for (std::size_t k = 0; k < radial.coefficients.size(); ++k) {
      f->addGlobalParameter(tag + "a" + std::to_string(k), radial.coefficients[k]);
    }
    for (std::size_t i = 0; i < sys.particles.size(); ++i) f->addParticle(static_cast<int>(i), {});
    add_external(f);
  }
  if (external_terms > 0) {
    m.term_names.push_back("external");
    m.term_groups.push_back(1 << kExternalGroup);
  }

  static const bool plugins_loaded = [] {
    OpenMM::Platform::loadPluginsFromDirectory(OpenMM::Platform::getDefaultPluginsDirectory());
    OpenMM::Platform::loadPluginsFromDirectory(DELI_OPENMM_PLUGIN_DIR);
    return true;
  }();
  (void)plugins_loaded;
  const std::string name = platform == Platform::reference ? "Reference" : "CPU";
  OpenMM::Platform* chosen = nullptr;
  try {
    chosen = &OpenMM::Platform::getPlatformByName(name);
  } catch (const OpenMM::OpenMMException&) {
    throw UnsupportedModel("OpenMM's " + name +
                           " platform is not available (install libopenmm-plugins)");
  }
  m.platform_name = name;
  m.platform = chosen;
  if (platform == Platform::cpu) m.properties = {{"Threads", "1"}};
  for (const Constraint& rod : rods) m.system.addConstraint(rod.i, rod.j, rod.length);
  m.integrator = std::make_unique<OpenMM::VerletIntegrator>(0.001);
  m.integrator->setConstraintTolerance(constraint_tolerance);
  m.context = std::make_unique<OpenMM::Context>(m.system, *m.integrator, *chosen, m.properties);
}

OpenMMBridge::~OpenMMBridge() = default;

std::string OpenMMBridge::name() const {
  return "OpenMM " + impl_->platform_name;
}

EngineEvaluation OpenMMBridge::evaluate(const std::vector<Vec3>& position) {
  Impl& m = *impl_;
  EngineEvaluation e;
  e.engine = name();
  auto energy_at = [&](double scale) {
    std::vector<Vec3> scaled = position;
    for (Vec3& x : scaled) x *= scale;
    if (m.periodic) {
      m.context->setPeriodicBoxVectors(OpenMM::Vec3(m.box_length.x * scale, 0, 0),
                                       OpenMM::Vec3(0, m.box_length.y * scale, 0),
                                       OpenMM::Vec3(0, 0, m.box_length.z * scale));
    }
    m.context->setPositions(to_openmm(scaled));
    // deli's external fields, as LAMMPS' fix gravity and fix addforce, add nothing to the
    // virial: the energy under scaling is that of the other terms.
    return m.context->getState(OpenMM::State::Energy, false, 0xffff & ~(1 << kExternalGroup))
        .getPotentialEnergy();
  };
  // OpenMM reports no virial: W = -dU/d(ln s) under uniform scaling of positions and box,
  // a central difference in ln s. The step balances truncation (h^2) against rounding
  // (precision / h).
  // In double precision (Reference) a step of 1e-6 gives W to about 1e-9. In single
  // precision (CPU) the energy's rounding needs a step of 1e-3, where the h^2 error alone
  // reached 1.2e-3 of W (FENE bonds, inputs/lj_chains/melt.toml): Richardson's
  // extrapolation from steps h and 2h cancels it, leaving O(h^4).
  auto slope = [&](double h) {
    return -(energy_at(std::exp(h)) - energy_at(std::exp(-h))) / (2.0 * h);
  };
  if (m.platform_name == "Reference") {
    e.virial = slope(1e-6);
  } else {
    const double h = 1e-3;
    e.virial = (4.0 * slope(h) - slope(2.0 * h)) / 3.0;
  }

  energy_at(1.0);
  const OpenMM::State state = m.context->getState(OpenMM::State::Energy | OpenMM::State::Forces);
  e.potential = state.getPotentialEnergy();
  e.force = from_openmm(state.getForces());
  for (std::size_t t = 0; t < m.term_names.size(); ++t) {
    e.term_names.push_back(m.term_names[t]);
    e.term_energies.push_back(
        m.context->getState(OpenMM::State::Energy, false, m.term_groups[t]).getPotentialEnergy());
  }
  return e;
}

std::vector<Vec3> OpenMMBridge::run_nve(const std::vector<Vec3>& position,
                                        const std::vector<Vec3>& velocity, int steps, double dt) {
  Impl& m = *impl_;
  const EngineEvaluation start = evaluate(position);
  std::vector<Vec3> half_step_back(velocity.size());
  for (std::size_t i = 0; i < velocity.size(); ++i) {
    half_step_back[i] = velocity[i] - start.force[i] * (0.5 * dt / m.mass[i]);
  }
  auto* verlet = static_cast<OpenMM::VerletIntegrator*>(m.integrator.get());
  verlet->setStepSize(dt);
  m.context->setPositions(to_openmm(position));
  m.context->setVelocities(to_openmm(half_step_back));
  verlet->step(steps);
  std::vector<Vec3> end = from_openmm(m.context->getState(OpenMM::State::Positions).getPositions());
  for (int a = 0; a < 3; ++a) {
    if (!m.padded[a]) continue;
    double lo = end[0][a], hi = end[0][a];
    for (const Vec3& x : end) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
    if (hi - lo + m.cutoff >= m.box_length[a]) {
      throw UnsupportedModel(
          "atoms spread along an open axis beyond the periodic length OpenMM was given for it; "
          "use fewer --steps");
    }
  }
  return end;
}

EnergySeries OpenMMBridge::run_langevin(const std::vector<Vec3>& position,
                                        const std::vector<Vec3>& velocity, const LangevinRun& run) {
  Impl& m = *impl_;
  if (run.seed <= 0) throw std::invalid_argument("OpenMM's seed must be positive (0: random)");
  // A context of its own: the Verlet one stays as it was.
  OpenMM::LangevinMiddleIntegrator langevin(run.temperature / kBoltzmannKJPerMolK,
                                            1.0 / run.damping, run.timestep);
  langevin.setRandomNumberSeed(run.seed);
  langevin.setConstraintTolerance(m.integrator->getConstraintTolerance());
  OpenMM::Context context(m.system, langevin, *m.platform, m.properties);
  context.setPositions(to_openmm(position));
  context.setVelocities(to_openmm(velocity));
  langevin.step(run.equilibration);
  EnergySeries series;
  for (int s = 0; s < run.samples; ++s) {
    langevin.step(run.every);
    const OpenMM::State state = context.getState(OpenMM::State::Energy);
    series.potential.push_back(state.getPotentialEnergy());
    series.kinetic.push_back(state.getKineticEnergy());
  }
  return series;
}

}  // namespace deli
