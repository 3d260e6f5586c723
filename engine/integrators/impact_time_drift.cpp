#include "integrators/impact_time_drift.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace deli {

namespace {

// |d + t v| = length, the first root after 0 with d outside (approaching from outside).
std::optional<double> reaching_from_outside(const Vec3& d, const Vec3& v, double length) {
  const double b = dot(d, v);
  if (b >= 0) return std::nullopt;  // leaving or tangent: never closes
  const double c = norm2(d) - length * length;
  if (c <= 0) return 0.0;  // touching (or overlapped by rounding) and approaching
  const double a = norm2(v);
  const double discriminant = b * b - a * c;
  if (discriminant < 0) return std::nullopt;  // passes by
  // The smaller root (-b - sqrt(disc)) / a, written without cancellation.
  return c / (-b + std::sqrt(discriminant));
}

}  // namespace

std::optional<double> closing_time(const Constraint& c, const Vec3& d, const Vec3& v) {
  switch (c.kind) {
    case ConstraintKind::sphere_pair:
    case ConstraintKind::outside_sphere:
      return reaching_from_outside(d, v, c.length);
    case ConstraintKind::plane: {
      const double w = dot(c.normal, v);
      if (w >= 0) return std::nullopt;
      const double gap = dot(c.normal, d) - c.length;
      return gap <= 0 ? 0.0 : gap / -w;
    }
    case ConstraintKind::inside_sphere: {
      // |d + t v| = length from inside: the larger root, always there for v != 0.
      const double a = norm2(v);
      if (!(a > 0)) return std::nullopt;
      const double b = dot(d, v);
      const double c0 = norm2(d) - c.length * c.length;  // <= 0 inside
      if (c0 >= 0 && b > 0) return 0.0;                  // on (or past) the wall, going out
      const double root = std::sqrt(std::max(0.0, b * b - a * c0));
      return b > 0 ? -c0 / (b + root) : (root - b) / a;
    }
    case ConstraintKind::rod:
    case ConstraintKind::anchor:
    case ConstraintKind::linear_pair:
      break;
  }
  throw std::logic_error(std::string("closing_time: a ") + kind_name(c.kind) +
                         " row has no straight-flight contact time");
}

void ImpactTimeDrift::schedule(std::int32_t row, double now, double h) {
  const Constraint& c = (*rows_)[row];
  const Vec3 xi = position_[c.i] + velocity_[c.i] * (now - clock_[c.i]);
  Vec3 d, v;
  if (c.j >= 0) {
    const Vec3 xj = position_[c.j] + velocity_[c.j] * (now - clock_[c.j]);
    d = box_->minimum_image(xi - xj);
    v = velocity_[c.i] - velocity_[c.j];
  } else {
    d = xi - c.point;
    v = velocity_[c.i];
  }
  const std::optional<double> t = closing_time(c, d, v);
  if (!t || now + *t > h) return;
  queue_.push_back({now + *t, row, stamp_[c.i], c.j >= 0 ? stamp_[c.j] : 0});
  std::push_heap(queue_.begin(), queue_.end(), [](const Event& a, const Event& b) {
    return a.time != b.time ? a.time > b.time : a.row > b.row;
  });
}

DriftOutcome ImpactTimeDrift::run(const std::vector<Constraint>& rows, const Particles& particles,
                                  const Box& box, double h, const std::vector<Vec3>& q,
                                  std::vector<Vec3>& p, std::vector<Vec3>& x,
                                  std::int64_t max_events, std::int64_t step,
                                  const std::vector<Vec3>* acceleration) {
  const std::size_t n = particles.size();
  rows_ = &rows;
  box_ = &box;
  position_ = q;
  clock_.assign(n, 0.0);
  velocity_.resize(n);
  for (std::size_t i = 0; i < n; ++i) velocity_[i] = p[i] * (1.0 / particles.mass[i]);
  stamp_.assign(n, 0);
  rows_of_.resize(n);
  for (auto& r : rows_of_) r.clear();
  for (std::size_t r = 0; r < rows.size(); ++r) {
    rows_of_[rows[r].i].push_back(static_cast<std::int32_t>(r));
    if (rows[r].j >= 0) rows_of_[rows[r].j].push_back(static_cast<std::int32_t>(r));
  }
  queue_.clear();
  for (std::size_t r = 0; r < rows.size(); ++r) schedule(static_cast<std::int32_t>(r), 0.0, h);

  DriftOutcome out;
  out.path.assign(n, 0.0);
  struct Vertex {
    std::int64_t k;
    std::int32_t particle;
    Vec3 at;
  };
  std::vector<Vertex> vertices;
  auto advance = [&](std::int32_t i, double t) {
    out.path[i] += norm(velocity_[i]) * (t - clock_[i]);
    position_[i] += velocity_[i] * (t - clock_[i]);
    clock_[i] = t;
  };
  const auto later = [](const Event& a, const Event& b) {
    return a.time != b.time ? a.time > b.time : a.row > b.row;
  };
  while (!queue_.empty()) {
    std::pop_heap(queue_.begin(), queue_.end(), later);
    const Event e = queue_.back();
    queue_.pop_back();
    const Constraint& c = rows[e.row];
    if (e.stamp_i != stamp_[c.i] || (c.j >= 0 && e.stamp_j != stamp_[c.j])) continue;  // stale
    advance(c.i, e.time);
    if (c.j >= 0) advance(c.j, e.time);
    const ConstraintValue value = evaluate(c, position_.data(), box);
    const double inverse_mass =
        1.0 / particles.mass[c.i] + (c.j >= 0 ? 1.0 / particles.mass[c.j] : 0.0);
    const double approach = dot(value.u, velocity_[c.i] - (c.j >= 0 ? velocity_[c.j] : Vec3{}));
    if (!(approach < 0)) continue;  // grazing to rounding: nothing to reflect
    if (++out.events > max_events) {
      throw SimulationError("step " + std::to_string(step) + ": more than " +
                            std::to_string(max_events) +
                            " contact events in one step of the impact-time drift (a "
                            "particle held between rows exactly its size apart bounces for "
                            "ever); use [integrator] contact = \"paper\"");
    }
    // Elastic: the normal relative velocity at contact reverses; the impulse acts along the
    // contact normal, equal and opposite on a pair.
    double after = -approach;
    if (acceleration) {
      const std::vector<Vec3>& a = *acceleration;
      const double a_n = dot(value.u, a[c.i] - (c.j >= 0 ? a[c.j] : Vec3{}));
      const double at_contact = approach + (e.time - 0.5 * h) * a_n;
      const double corrected = -approach + (h - 2.0 * e.time) * a_n;
      // Where the force would have turned the pair round before contact, or would not let
      // it separate after, the straight drift and the force disagree by more than the
      // correction can mend: the plain reflection keeps the gap.
      if (at_contact < 0 && corrected > 0) {
        after = corrected;
      } else if (a_n != 0) {
        ++out.plain;
      }
    }
    const double impulse = (after - approach) / inverse_mass;
    p[c.i] += value.u * impulse;
    velocity_[c.i] = p[c.i] * (1.0 / particles.mass[c.i]);
    vertices.push_back({stamp_[c.i]++, c.i, position_[c.i]});
    if (c.j >= 0) {
      p[c.j] -= value.u * impulse;
      velocity_[c.j] = p[c.j] * (1.0 / particles.mass[c.j]);
      vertices.push_back({stamp_[c.j]++, c.j, position_[c.j]});
      out.virial += (value.gap + c.length) * impulse;
    }
    for (std::int32_t r : rows_of_[c.i]) schedule(r, e.time, h);
    if (c.j >= 0) {
      for (std::int32_t r : rows_of_[c.j]) {
        if (rows[r].i != c.i && rows[r].j != c.i) schedule(r, e.time, h);
      }
    }
  }
  x.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (stamp_[i] == 0) {
      // No event: the free step, written as GVI's own position update writes it.
      x[i] = q[i] + p[i] * (h / particles.mass[i]);
      out.path[i] = norm(x[i] - q[i]);
    } else {
      const auto k = static_cast<std::int32_t>(i);
      advance(k, h);
      x[i] = position_[i];
    }
  }
  std::int64_t most = 0;
  for (const Vertex& v : vertices) most = std::max(most, v.k + 1);
  out.vertices.assign(static_cast<std::size_t>(most), x);
  for (const Vertex& v : vertices) out.vertices[v.k][v.particle] = v.at;
  return out;
}

}  // namespace deli
