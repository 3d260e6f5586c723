#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "constraints/constraint.hpp"
#include "system/particles.hpp"

namespace deli {

// The exact flow of hard spheres and hard walls over one drift of length h: every particle
// flies straight at constant velocity, and a row that closes reflects the pair elastically
// at the instant and configuration of contact (events in time order, several per particle
// if they come). GVI's `contact = "impact_time"` drift between its two half kicks.
// Rows: sphere pairs, planes, inside and outside spheres (no rods, strings or linearised
// rows: their flow is not a straight flight).
struct DriftOutcome {
  std::int64_t events = 0;
  // Contacts the force correction could not turn round (below): reflected plainly.
  std::int64_t plain = 0;
  double virial = 0.0;  // sum over events of (separation at contact) x impulse
  // Per particle, the length of its path through the drift (for the reach checks).
  std::vector<double> path;
  // Per particle, where its k-th event happened (k from 0); `vertices[k]` holds the end
  // position for particles with fewer events: each is one set of positions the path passed.
  std::vector<std::vector<Vec3>> vertices;
};

class ImpactTimeDrift {
 public:
  // Moves positions q (copied into x) with momenta p for time h through the rows' contacts;
  // p receives the contact impulses. Stops with an error past `max_events` events (a
  // particle pinned between two rows exactly its size apart bounces for ever).
  // `acceleration` (F/m at q, or null): the drift's momenta are the half-kicked p + h/2 F,
  // so a contact at time t inside the step would reflect a velocity that already holds
  // (h/2 - t) F/m too much; the impulse reflects the velocity at contact instead, making
  // the normal velocity after it -w + (h - 2t) a_n (w the drift's, a_n the normal relative
  // acceleration): the step's velocity error at a contact goes from O(h) to O(h^2).
  DriftOutcome run(const std::vector<Constraint>& rows, const Particles& particles, const Box& box,
                   double h, const std::vector<Vec3>& q, std::vector<Vec3>& p, std::vector<Vec3>& x,
                   std::int64_t max_events, std::int64_t step,
                   const std::vector<Vec3>* acceleration = nullptr);

 private:
  struct Event {
    double time;
    std::int32_t row;
    std::int64_t stamp_i, stamp_j;
  };
  void schedule(std::int32_t row, double now, double h);

  const std::vector<Constraint>* rows_ = nullptr;
  const Box* box_ = nullptr;
  std::vector<Vec3> position_;  // at the particle's own clock
  std::vector<double> clock_;
  std::vector<Vec3> velocity_;
  std::vector<std::int64_t> stamp_;  // events so far per particle (stale-event check)
  std::vector<std::vector<std::int32_t>> rows_of_;
  std::vector<Event> queue_;  // a binary heap, earliest first, ties by row index
};

// The time after which a row with relative position/velocity closes, or nothing: the exact
// root of the gap along straight flight. `d` is x_i - x_j (pairs) or x_i - point (walls), `v`
// the matching velocity. A row touching (or overlapped by rounding) and approaching closes at
// 0; one touching and leaving does not close (inside a sphere it closes when it reaches the
// far side).
std::optional<double> closing_time(const Constraint& c, const Vec3& d, const Vec3& v);

}  // namespace deli
