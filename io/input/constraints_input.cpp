#include "input/constraints_input.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "core/error.hpp"

namespace deli {

namespace {

Vec3 vec3(TomlTable& t, const std::string& key) {
  const auto v = t.numbers(key, 3);
  return {v[0], v[1], v[2]};
}

std::int32_t atom_index(TomlTable& t, const std::string& key, double id,
                        const std::unordered_map<std::int64_t, std::int32_t>& index_of) {
  const auto it = index_of.find(static_cast<std::int64_t>(id));
  if (id != std::floor(id) || it == index_of.end()) {
    t.fail("no atom with id " + std::to_string(static_cast<long long>(id)) + " in the system", key);
  }
  return it->second;
}

void require_open(TomlTable& t, const Box& box, const Vec3& direction, const std::string& what) {
  for (int a = 0; a < 3; ++a) {
    if (box.periodic(a) && direction[a] != 0.0) {
      t.fail(what + " needs the box open along " + std::string(1, "xyz"[a]) +
             " (positions are wrapped along periodic axes); use boundary with 'f' there");
    }
  }
}

// Rods that cannot all hold, found before a solver fails on them: one pair joined by two
// rods, or three atoms joined in a triangle whose lengths break the triangle inequality.
void check_rods_can_hold(const std::vector<Constraint>& rods, const Particles& p,
                         const TomlTable& t) {
  const std::string key = t.has("rods") ? "rods" : "bonds";
  std::map<std::pair<std::int32_t, std::int32_t>, double> length;
  std::unordered_map<std::int32_t, std::vector<std::int32_t>> joined;
  for (const Constraint& c : rods) {
    if (c.kind != ConstraintKind::rod) continue;
    if (!length.emplace(std::pair{c.i, c.j}, c.length).second) {
      t.fail("infeasible constraints: atoms " + std::to_string(p.id[c.i]) + " and " +
                 std::to_string(p.id[c.j]) +
                 " are joined by two rods (a bond made rigid and a rod, or a rod given twice); "
                 "give each pair one rod",
             key);
    }
    joined[c.i].push_back(c.j);
    joined[c.j].push_back(c.i);
  }
  auto rod = [&](std::int32_t a, std::int32_t b) {
    const auto it = length.find({std::min(a, b), std::max(a, b)});
    return it == length.end() ? -1.0 : it->second;
  };
  for (const auto& [pair, ij] : length) {
    const auto [i, j] = pair;
    for (const std::int32_t k : joined[i]) {
      if (k <= j) continue;  // each triangle once: i < j < k
      const double ik = rod(i, k), jk = rod(j, k);
      if (jk < 0) continue;
      const double longest = std::max({ij, ik, jk});
      if (2.0 * longest > (ij + ik + jk) * (1.0 + 1e-12)) {
        t.fail("infeasible constraints: the rods joining atoms " + std::to_string(p.id[i]) + ", " +
                   std::to_string(p.id[j]) + " and " + std::to_string(p.id[k]) + " (lengths " +
                   std::to_string(ij) + ", " + std::to_string(ik) + ", " + std::to_string(jk) +
                   ") cannot form a triangle: the longest exceeds the sum of the other two",
               key);
      }
    }
  }
}

}  // namespace

ConstraintSet read_constraints(std::optional<TomlTable> table, System& system, bool& rigid_bonds) {
  ConstraintSet set;
  rigid_bonds = false;
  if (!table) return set;
  TomlTable& t = *table;
  Particles& p = system.particles;
  std::unordered_map<std::int64_t, std::int32_t> index_of;
  for (std::size_t i = 0; i < p.size(); ++i) index_of[p.id[i]] = static_cast<std::int32_t>(i);

  auto add_rod = [&](std::int32_t i, std::int32_t j, std::optional<double> length) {
    Constraint c;
    c.kind = ConstraintKind::rod;
    c.i = std::min(i, j);
    c.j = std::max(i, j);
    c.length = length.value_or(norm(system.box.minimum_image(p.position[i] - p.position[j])));
    set.equalities.push_back(c);
  };

  rigid_bonds = t.choice("bonds", {"flexible", "rigid"}, "flexible") == "rigid";
  if (rigid_bonds) {
    std::optional<double> length;
    if (t.has("rod_length")) {
      length = t.number("rod_length");
      if (!(*length > 0)) t.fail("must be positive", "rod_length");
    }
    for (const Bond& b : system.topology.bonds) add_rod(b.i, b.j, length);
  }
  for (TomlTable& r : t.tables("rods")) {
    const auto atoms = r.numbers("atoms", 2);
    const std::int32_t i = atom_index(r, "atoms", atoms[0], index_of);
    const std::int32_t j = atom_index(r, "atoms", atoms[1], index_of);
    if (i == j) r.fail("a rod joins two different atoms", "atoms");
    std::optional<double> length;
    if (r.has("length")) {
      length = r.number("length");
      if (!(*length > 0)) r.fail("a rod's length must be positive", "length");
    }
    add_rod(i, j, length);
    r.finish();
  }
  check_rods_can_hold(set.equalities, p, t);
  for (TomlTable& a : t.tables("anchors")) {
    Constraint c;
    c.kind = ConstraintKind::anchor;
    c.i = atom_index(a, "atom", a.number("atom"), index_of);
    c.point = vec3(a, "point");
    require_open(a, system.box, {1, 1, 1}, "an anchor string");
    c.length = a.has("length") ? a.number("length") : norm(p.position[c.i] - c.point);
    if (!(c.length > 0)) a.fail("must be positive", "length");
    set.equalities.push_back(c);
    a.finish();
  }
  for (const Constraint& c : set.equalities) {
    if (c.kind == ConstraintKind::rod) set.unconstrained_pairs.push_back({c.i, c.j});
  }

  // Without hard spheres, particles are points: walls and strings see their centres.
  std::fill(p.radius.begin(), p.radius.end(), 0.0);
  for (AtomType& type : system.atom_types) type.radius = 0.0;
  if (auto hs = t.table("hard_spheres")) {
    set.hard_spheres = true;
    const int types = static_cast<int>(system.atom_types.size());
    std::vector<double> radius(static_cast<std::size_t>(types));
    if (hs->has("diameter")) {
      const double d = hs->number("diameter");
      if (!(d > 0)) hs->fail("must be positive", "diameter");
      std::fill(radius.begin(), radius.end(), 0.5 * d);
    } else {
      radius = hs->numbers("radii", static_cast<std::size_t>(types));
      for (double r : radius) {
        if (!(r > 0)) hs->fail("radii must be positive", "radii");
      }
    }
    for (std::size_t i = 0; i < p.size(); ++i) p.radius[i] = radius[p.type[i]];
    for (int k = 0; k < types; ++k) system.atom_types[k].radius = radius[k];
    hs->finish();
    // Bonded pairs are held by their bond, not by non-overlap.
    for (const Bond& b : system.topology.bonds) {
      set.unconstrained_pairs.push_back({std::min(b.i, b.j), std::max(b.i, b.j)});
    }
  }
  std::sort(set.unconstrained_pairs.begin(), set.unconstrained_pairs.end());
  set.unconstrained_pairs.erase(
      std::unique(set.unconstrained_pairs.begin(), set.unconstrained_pairs.end()),
      set.unconstrained_pairs.end());

  for (TomlTable& w : t.tables("walls")) {
    Wall wall;
    const std::string type = w.choice("type", {"plane", "inside_sphere", "outside_sphere"});
    if (type == "plane") {
      wall.kind = ConstraintKind::plane;
      wall.point = w.has("point") ? vec3(w, "point") : Vec3{};
      wall.normal = vec3(w, "normal");
      if (std::abs(norm(wall.normal) - 1.0) > 1e-12) {
        w.fail("must be a unit vector (its length is " + std::to_string(norm(wall.normal)) + ")",
               "normal");
      }
      require_open(w, system.box, wall.normal, "a plane wall");
    } else {
      wall.kind =
          type == "inside_sphere" ? ConstraintKind::inside_sphere : ConstraintKind::outside_sphere;
      wall.point = w.has("center") ? vec3(w, "center") : Vec3{};
      wall.radius = w.number("radius");
      if (!(wall.radius > 0)) w.fail("must be positive", "radius");
      require_open(w, system.box, {1, 1, 1}, "a spherical wall");
    }
    w.finish();
    set.walls.push_back(wall);
  }

  set.linearized = t.boolean("linearized", false);
  if (auto tol = t.table("tolerance")) {
    set.tolerances.gap = tol->number("gap", set.tolerances.gap);
    set.tolerances.velocity = tol->number("velocity", set.tolerances.velocity);
    set.tolerances.solver = tol->number("solver", set.tolerances.solver);
    for (const auto& [key, value] :
         {std::pair{"gap", set.tolerances.gap}, std::pair{"velocity", set.tolerances.velocity},
          std::pair{"solver", set.tolerances.solver}}) {
      if (!(value > 0)) tol->fail("must be positive", key);
    }
    tol->finish();
  }
  if (auto lim = t.table("limits")) {
    SolverLimits& limits = set.limits;
    for (const auto& [key, value] :
         {std::pair{"newton", &limits.newton}, std::pair{"line_search", &limits.line_search},
          std::pair{"active_set_rounds", &limits.active_set_rounds},
          std::pair{"feasibility_rounds", &limits.feasibility_rounds},
          std::pair{"reflection_solves", &limits.reflection_solves},
          std::pair{"midpoint_passes", &limits.midpoint_passes},
          std::pair{"contact_time", &limits.contact_time},
          std::pair{"direct_settle_passes", &limits.direct_settle_passes},
          std::pair{"direct_landing_rounds", &limits.direct_landing_rounds}}) {
      const std::int64_t read = lim->integer(key, *value);
      if (read < 1 || read > 1000000) lim->fail("must be an integer from 1 to 1000000", key);
      *value = static_cast<int>(read);
    }
    // The QP's limit has no fixed default (10 n + 10 for n rows): absent, it stays 0.
    const std::int64_t qp = lim->integer("qp_iterations", limits.qp_iterations);
    if (qp < 0 || qp > 1000000 || (qp == 0 && lim->has("qp_iterations")))
      lim->fail("must be an integer from 1 to 1000000", "qp_iterations");
    limits.qp_iterations = static_cast<int>(qp);
    lim->finish();
  }
  t.finish();
  return set;
}

}  // namespace deli
