#include "constraints/equality_rank.hpp"

#include <Eigen/Dense>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include "constraints/union_find.hpp"

namespace deli {

namespace {

struct Component {
  std::vector<std::size_t> rows;
  std::vector<std::int32_t> particles;
  bool pair_rows_only = true;
};

// The rank of a component's Jacobian; rows with a zero gradient (coincident atoms) count
// as dependent. The threshold is relative to the unit gradients every row has.
std::size_t component_rank(const Component& component, const std::vector<Constraint>& rows,
                           const Vec3* x, const Box& box) {
  std::unordered_map<std::int32_t, Eigen::Index> column;
  for (std::int32_t i : component.particles) {
    column.emplace(i, static_cast<Eigen::Index>(3 * column.size()));
  }
  Eigen::MatrixXd jacobian =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(component.rows.size()),
                            static_cast<Eigen::Index>(3 * component.particles.size()));
  for (std::size_t r = 0; r < component.rows.size(); ++r) {
    const Constraint& c = rows[component.rows[r]];
    const Vec3 u = evaluate(c, x, box).u;
    const auto row = static_cast<Eigen::Index>(r);
    for (int a = 0; a < 3; ++a) {
      jacobian(row, column.at(c.i) + a) += u[a];
      if (c.j >= 0) jacobian(row, column.at(c.j) + a) -= u[a];
    }
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(jacobian);
  qr.setThreshold(1e-10);
  return static_cast<std::size_t>(qr.rank());
}

}  // namespace

std::size_t independent_equalities(const std::vector<Constraint>& rows, const Vec3* x,
                                   std::size_t particle_count, const Box& box) {
  std::vector<std::int32_t> parent(particle_count);
  std::iota(parent.begin(), parent.end(), 0);
  for (const Constraint& c : rows) {
    if (c.j >= 0) parent[union_find_root(parent, c.i)] = union_find_root(parent, c.j);
  }
  std::unordered_map<std::int32_t, Component> components;
  std::vector<char> seen(particle_count, 0);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Constraint& c = rows[r];
    Component& component = components[union_find_root(parent, c.i)];
    component.rows.push_back(r);
    component.pair_rows_only = component.pair_rows_only && c.j >= 0;
    for (std::int32_t i : {c.i, c.j}) {
      if (i >= 0 && !seen[i]) {
        seen[i] = 1;
        component.particles.push_back(i);
      }
    }
  }
  std::size_t rank = 0;
  for (const auto& [key, component] : components) {
    // A connected component of k atoms joined by k - 1 pair rows is a tree: its rows are
    // independent (each adds an atom the others do not move) unless a rod has no length.
    const bool tree =
        component.pair_rows_only && component.rows.size() + 1 == component.particles.size();
    rank += tree ? component.rows.size() : component_rank(component, rows, x, box);
  }
  return rank;
}

}  // namespace deli
