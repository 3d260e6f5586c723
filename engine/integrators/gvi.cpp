#include "integrators/gvi.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "constraints/clusters.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/phase_timer.hpp"
#include "integrators/contact_group.hpp"
#include "integrators/gvi_particle_passes.hpp"
#include "integrators/shadow_correction.hpp"
#include "solvers/cluster_matrices.hpp"

namespace deli {

namespace {
// Particles' vectors as their numbers, 3 doubles a particle (gvi_particle_passes.hpp).
static_assert(sizeof(Vec3) == 3 * sizeof(double));
double* numbers(std::vector<Vec3>& v) {
  return reinterpret_cast<double*>(v.data());
}
const double* numbers(const std::vector<Vec3>& v) {
  return reinterpret_cast<const double*>(v.data());
}
const double* numbers_of(const Vec3* v) {
  return reinterpret_cast<const double*>(v);
}

// The held rows' position impulses, or null when no row was held, which leaves `impulse`
// empty: the passes read +0 then (what the solve's zeroed vector holds).
const double* held_impulses(const GviWorkspace& ws) {
  return ws.impulse.empty() ? nullptr : numbers(ws.impulse);
}

// The end positions' pass over the workspace: x = q + (half + impulse) (h / m), with the
// list's test where the list is built for these particles and the reach's where given.
gvi_passes::EndPositions end_positions_pass(GviWorkspace& ws, const Particles& P, double h,
                                            const NeighborList& list, bool built,
                                            const double* reach_limit2) {
  gvi_passes::EndPositions pass;
  pass.h = h;
  pass.q = numbers(ws.q);
  pass.half = numbers(ws.half);
  pass.impulse = held_impulses(ws);
  pass.mass = P.mass.data();
  pass.reach_limit2 = reach_limit2;
  pass.at_build = built ? numbers(list.positions_at_build()) : nullptr;
  pass.list_limit2 = list.valid_distance2();
  pass.x = numbers(ws.x);
  return pass;
}

// The start pass over the workspace from the particles and the forces f: q = position and the
// momenta v m, and what the caller asks of the rest (half kick, free step, prediction...).
gvi_passes::StepStart step_start_pass(GviWorkspace& ws, const Particles& P, double h,
                                      const std::vector<Vec3>& f) {
  gvi_passes::StepStart pass;
  pass.h = h;
  pass.position = numbers(P.position);
  pass.velocity = numbers(P.velocity);
  pass.mass = P.mass.data();
  pass.force = numbers(f);
  pass.q = numbers(ws.q);
  return pass;
}

// Momentum p after a half kick by force f, p + h/2 f, and the free step h M^-1 of such a
// momentum, for the passes over some particles (a reflection's prediction, the midpoint's).
// The passes over all of them make the same numbers in vectors (gvi_passes::step_start and
// half_kick, tested bit for bit against these): numbers one pass keeps stand for those another
// would make (start_step's for solve_held_positions', its prediction for predict_reflected's).
Vec3 half_kicked(const Vec3& p, const Vec3& f, double h) {
  return p + f * (0.5 * h);
}
Vec3 free_step(const Vec3& momentum, double h, double mass) {
  return momentum * (h / mass);
}
}  // namespace

Gvi::Gvi(const ForceField& force_field, ConstraintSet constraints, const GviOptions& options,
         const Particles& particles)
    : ConstrainedIntegrator(force_field, std::move(constraints), options.timestep, options.skin,
                            options.reflection, options.energy, particles),
      feasibility_(options.feasibility),
      lagrangian_(options.lagrangian),
      reflections_(options.reflections),
      constrained_predictor_(options.constrained_predictor),
      contact_(options.contact),
      shadow_remainder_steps_(options.shadow_remainder_steps) {
  if (contact_ == ContactTreatment::impact_time) refuse_impact_times_unless_supported();
}

void Gvi::step(System& system, bool tally) {
  if (contact_ == ContactTreatment::impact_time) return step_with_impact_times(system, tally);
  PhaseTimer& timer = phase_timer();
  const Phase outer = timer.enter(Phase::prediction);
  step_virial_ = 0.0;
  start_step(system);
  timer.enter(Phase::active_set);
  find_active_set(system);
  find_smooth_set(system);
  timer.enter(Phase::position_update);
  update_positions(system);
  timer.enter(Phase::momentum_update);
  update_momenta(system, tally);
  ++stats_.steps;
  // Same size: the buffer (and pointers into it) stays. Only linearised rows read it during
  // the checks; otherwise the start positions, no longer needed, are swapped in.
  if (constraints_.linearized) previous_positions_ = ws_.q;
  timer.enter(Phase::constraint_checks);
  check_constraints(system, tally);
  if (!constraints_.linearized) std::swap(previous_positions_, ws_.q);
  finish_step();
  timer.enter(outer);
}

// Displacement of the unconstrained forward step from (q, p): D1Ld(q, q + d) + p = 0.
// Verlet: d = h M^-1 (p + h/2 F(q)). Midpoint: d = h M^-1 (p + h/2 F(q + d/2)), by fixed
// point from the Verlet guess.
void Gvi::free_displacement(System& system, const std::vector<Vec3>& momenta, std::vector<Vec3>& d,
                            const std::function<void(std::size_t, std::size_t)>& after) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  const std::vector<Vec3>& f = engine_.force();
  d.resize(n);
  // The step is captured by value here and below: a double behind a reference could alias
  // the doubles the loop stores, and would be loaded again at every particle.
  const bool verlet = lagrangian_ != Lagrangian::midpoint;
  for_each_chunk(n, chunks_for_cheap(n), [&, h, verlet](int, std::size_t begin, std::size_t end) {
    gvi_passes::half_kick(h, numbers(momenta), numbers(f), P.mass.data(), nullptr, numbers(d),
                          begin, end);
    if (verlet) after(begin, end);
  });
  if (verlet) return;
  std::vector<Vec3>& mid = ws_.prediction_mid;
  mid.resize(n);
  iterate_midpoint(system, 0, [&] {
    parallel_for(n, [&](std::size_t i) { mid[i] = P.position[i] + d[i] * 0.5; });
    engine_.forces_at(system, mid, ws_.prediction_force);
    const std::vector<Vec3>& f_mid = ws_.prediction_force;
    return ordered_max(n, 0.0, [&, h](std::size_t i) {
      const Vec3 next = free_step(half_kicked(momenta[i], f_mid[i], h), h, P.mass[i]);
      const double change = norm(next - d[i]);
      d[i] = next;
      return change;
    });
  });
  for_each_chunk(n, chunks_for_cheap(n),
                 [&](int, std::size_t begin, std::size_t end) { after(begin, end); });
}

// The predictor: the unconstrained step, or (predictor = "constrained") that step with the
// equality rows (rods, strings) solved, which lands where the step will really go when rods
// pull, so fewer contacts are missed.
void Gvi::predict(System& system, const std::vector<Vec3>& momenta, std::vector<Vec3>& x,
                  bool constrained, bool again) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  std::vector<Vec3>& d = ws_.displacement;
  const bool solved = constrained && !constraints_.equalities.empty();
  std::vector<Vec3>& j = ws_.prediction_kick;
  // Again in the same step: only the chains whose free displacement changed (those the
  // reflections touched) are solved again; the others' kicks would come out the same.
  const bool reuse = solved && again && ws_.kicked_displacement.size() == n && j.size() == n;
  x.resize(n);
  if (reuse) ws_.displacement_changed.resize(n);
  // x = q + d, and (reuse) which displacements changed, particle by particle.
  auto after_displacement = [&, reuse](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) x[i] = P.position[i] + d[i];
    for (std::size_t i = begin; reuse && i < end; ++i) {
      const Vec3& a = d[i];
      const Vec3& b = ws_.kicked_displacement[i];
      ws_.displacement_changed[i] = !(a.x == b.x && a.y == b.y && a.z == b.z);
    }
  };
  // Verlet: in the free step's own pass (one job of the team, not three).
  free_displacement(system, momenta, d, after_displacement);
  if (!solved) return;
  if (!reuse) j.assign(n, Vec3{});
  ws_.all_equality.assign(constraints_.equalities.size(), true);
  solve_positions(system, constraints_.equalities, ws_.all_equality, P.position, d, j,
                  reuse ? &ws_.displacement_changed : nullptr);
  ws_.kicked_displacement.resize(n);
  parallel_for(n, [&, h = dt_](std::size_t i) {
    ws_.kicked_displacement[i] = d[i];
    x[i] += j[i] * (h / P.mass[i]);
  });
}

void Gvi::start_step(System& system) {
  Particles& P = system.particles;
  const std::size_t n = P.size();
  ws_.p.resize(n);
  // The free prediction first, even with the constrained predictor: it decides whether the
  // neighbour list still covers the step. Verlet: in the momenta's pass, predict's numbers,
  // and the start positions q copied in the same pass.
  bool prediction_covered = false;  // known to be covered (else asked below)
  bool q_copied = false;            // ws_.q holds P.position
  bool prediction_known = false;    // prediction_covered is neighbors_cover's answer
  // Read only by the energy restoration of landed rows (inequality rows alone land) and the
  // impact-time step.
  const bool keep_start_momenta = (feasibility_ == Feasibility::restore && has_inequalities()) ||
                                  contact_ == ContactTreatment::impact_time;
  bool p_start_made = false;    // ws_.p_start holds ws_.p
  bool p_made = true;           // ws_.p holds the momenta
  bool prediction_read = true;  // the step reads the prediction and the list before x
  ws_.half_kicked = false;
  ws_.displacement2_of_prediction = false;
  if (steps_by_cluster(P)) {
    // Nothing in the step reads the list or the momenta before the forces at x: the position
    // update's cluster passes make q, the half kick and the free step (step_start's numbers)
    // and test x against the list, which the force evaluation rebuilds where x leaves it.
    // This pass of its own was a job of the team a step.
    ws_.q.resize(n);
    prediction_covered = engine_.neighbors().built_for(n);
    prediction_known = true;
    q_copied = true;
    p_made = false;
    prediction_read = false;
  } else if (lagrangian_ == Lagrangian::verlet) {
    const double h = dt_;
    const std::vector<Vec3>& f = engine_.force();
    ws_.q.resize(n);
    const NeighborList& list = engine_.neighbors();
    const bool listed = list.built_for(n);
    // Only the contact rows' search and the impact-time step read the prediction (and the
    // list before the forces at x): then the same pass tells whether the list covers it
    // (needs_rebuild's test, particle by particle), counted per chunk. Otherwise (rods alone,
    // or no row) the list is tested at x, where displaced() makes it, and rebuilt there by
    // the force evaluation if x leaves it: the free prediction, ignoring the rods' pull,
    // left the list more often (the rigid melt: 99 builds in 1000 steps, at x 89).
    const bool keep =
        has_inequalities() || constrained_predictor_ || contact_ == ContactTreatment::impact_time;
    if (keep) ws_.predicted.resize(n);
    const int chunks = chunks_for_cheap(n);
    // Rods alone (no reflection changes the momenta before the position update): the half
    // kick and free step that solve_held_positions starts from are the numbers made here,
    // kept in this pass instead of made in one of their own. Then nothing reads the momenta
    // before update_momenta makes them anew, but a prediction after a rebuild below: they are
    // stored only for it.
    const bool kick = !keep && !constraints_.equalities.empty();
    const bool zero = kick && !equalities_hold_every_particle(P);
    if (kick) {
      ws_.half.resize(n);
      ws_.free.resize(n);
      ws_.impulse.resize(n);
    }
    std::vector<std::size_t>& beyond = ws_.chunk_outgrown;
    beyond.assign(static_cast<std::size_t>(chunks), 0);
    // The numbers of half_kicked and free_step (free_displacement's d: predict() makes it
    // again where it reads it), in vectors.
    gvi_passes::StepStart pass = step_start_pass(ws_, P, h, f);
    pass.at_build = listed && keep ? numbers(list.positions_at_build()) : nullptr;
    pass.list_limit2 = list.valid_distance2();
    pass.p = kick ? nullptr : numbers(ws_.p);
    // Made in this pass, each thread on its own particles: copied after it by the calling
    // thread, the other threads' momenta crossed to its core and back every step.
    p_start_made = keep_start_momenta && !kick;
    if (p_start_made) ws_.p_start.resize(n);
    pass.p_start = p_start_made ? numbers(ws_.p_start) : nullptr;
    pass.half = kick ? numbers(ws_.half) : nullptr;
    pass.free = kick ? numbers(ws_.free) : nullptr;
    pass.impulse = zero ? numbers(ws_.impulse) : nullptr;
    pass.predicted = keep ? numbers(ws_.predicted) : nullptr;
    // The displacements the step's first collection of rows by particle reach starts from,
    // made here with the prediction: that collection's pass of its own was a job a step.
    // (Not where the constrained predictor replaces this prediction below.)
    const bool displacements = keep && particle_reaches() && !constrained_predictor_;
    if (displacements) ws_.displacement2.resize(n);
    pass.displacement2 = displacements ? ws_.displacement2.data() : nullptr;
    // And that collection's reaches from the last step's floor, and the particles'
    // displacements from the short list's anchors: its pass over the particles was a job a
    // step (6 % of the 4000-sphere fluid's loop on one thread).
    const bool reaches = displacements && ws_.reach_floor2 >= 0.0;
    const NearbyRows::Anchors anchors =
        reaches ? nearby_rows_.anchors_for(list, n) : NearbyRows::Anchors{};
    if (reaches) {
      ws_.particle_reach.resize(n);
      ws_.reach_limit2.resize(n);
      pass.reach_floor2 = ws_.reach_floor2;
      pass.gap_tolerance = constraints_.tolerances.gap;
      pass.reach = ws_.particle_reach.data();
      pass.reach_limit2 = ws_.reach_limit2.data();
      pass.anchor = numbers_of(anchors.anchor);
      pass.moved = anchors.moved;
    }
    ChunkSlots<double> largest2(static_cast<std::size_t>(chunks), 0.0);
    ChunkSlots<double> anchored_largest2(static_cast<std::size_t>(chunks), 0.0);
    for_each_chunk(n, chunks, [&](int c, std::size_t begin, std::size_t end) {
      const gvi_passes::StepStartTally tally = gvi_passes::step_start(pass, begin, end);
      beyond[static_cast<std::size_t>(c)] = tally.beyond_list;
      largest2[static_cast<std::size_t>(c)] = tally.largest2;
      anchored_largest2[static_cast<std::size_t>(c)] = tally.anchored_largest2;
    });
    ws_.displacement2_of_prediction = displacements;
    ws_.reaches_of_prediction = reaches;
    ws_.anchored = anchors.anchor != nullptr;
    ws_.prediction_largest2 = 0.0;
    for (const double m : largest2) ws_.prediction_largest2 = std::max(ws_.prediction_largest2, m);
    ws_.anchored_largest2 = 0.0;
    for (const double m : anchored_largest2) {
      ws_.anchored_largest2 = std::max(ws_.anchored_largest2, m);
    }
    // A rebuild below wraps the positions, which leaves these numbers as they are.
    ws_.half_kicked = kick;
    p_made = !kick;
    prediction_read = keep;
    prediction_covered =
        listed && std::all_of(beyond.begin(), beyond.end(), [](std::size_t k) { return k == 0; });
    // neighbors_cover's answer for the prediction: its test, made above (a list not built for
    // these particles covers nothing).
    prediction_known = true;
    q_copied = true;
  } else {
    parallel_for(n, [&](std::size_t i) { ws_.p[i] = P.velocity[i] * P.mass[i]; });
    predict(system, ws_.p, ws_.predicted, false);
  }
  // Without pair forces or hard spheres no pair is ever looked up: any motion is fine.
  const bool pairs_matter = engine_.neighbors().cutoff() > 0;
  if (pairs_matter && !prediction_covered &&
      (prediction_known || !engine_.neighbors_cover(ws_.predicted))) {
    // Where the step reads the prediction, made again from the wrapped positions, with the
    // start positions q copied and the new list's cover of it tested (needs_rebuild's test:
    // the list's build positions are these positions) in the same pass: three jobs a build
    // before. Verlet's free step (free_displacement's numbers) in the build's first job, each
    // chunk's right after its wrap; otherwise after the build.
    const bool verlet_in_build = prediction_read && p_made && lagrangian_ == Lagrangian::verlet;
    std::vector<Vec3>& d = ws_.displacement;
    std::vector<Vec3>& x = ws_.predicted;
    if (prediction_read) {
      d.resize(n);
      x.resize(n);
      ws_.q.resize(n);
    }
    const double limit2 = engine_.neighbors().valid_distance2();
    std::atomic<std::size_t> beyond{0};
    auto predicted_from = [&, limit2](std::size_t begin, std::size_t end) {
      std::size_t count = 0;
      for (std::size_t i = begin; i < end; ++i) {
        ws_.q[i] = P.position[i];
        x[i] = P.position[i] + d[i];
        count += !(norm2(x[i] - P.position[i]) <= limit2) ? 1 : 0;
      }
      if (count > 0) beyond.fetch_add(count, std::memory_order_relaxed);
    };
    const RangePass predict_in_build = [&, h = dt_](std::size_t begin, std::size_t end) {
      gvi_passes::half_kick(h, numbers(ws_.p), numbers(engine_.force()), P.mass.data(), nullptr,
                            numbers(d), begin, end);
      predicted_from(begin, end);
    };
    engine_.ensure_neighbors(system, true,
                             verlet_in_build ? &predict_in_build : nullptr);  // wraps P.position
    q_copied = false;
    ws_.displacement2_of_prediction = false;
    ws_.reaches_of_prediction = false;
    ws_.anchored = false;
    // Where nothing reads the prediction (rods alone: the list built for other particles),
    // the test at x follows.
    if (prediction_read) {
      if (!verlet_in_build) {
        if (!p_made) {
          parallel_for(n, [&](std::size_t i) { ws_.p[i] = P.velocity[i] * P.mass[i]; });
        }
        free_displacement(system, ws_.p, d, predicted_from);
      }
      q_copied = true;
      if (beyond.load(std::memory_order_relaxed) > 0) {
        throw SimulationError("step " + std::to_string(system.step + 1) +
                              ": a particle would move more than half the neighbour skin in one "
                              "step; increase [neighbor] skin or reduce the timestep");
      }
    }
  }
  if (!q_copied) copy_in_chunks(P.position, ws_.q);
  if (keep_start_momenta && !p_start_made) copy_in_chunks(ws_.p, ws_.p_start);
  if (constrained_predictor_) {
    predict(system, ws_.p, ws_.predicted, true);
    ws_.displacement2_of_prediction = false;
    ws_.reaches_of_prediction = false;
    ws_.anchored = false;
  }
  if (previous_positions_.size() != n) previous_positions_ = ws_.q;
  ws_.x_in_positions = false;
  ws_.changed_cover_known = false;
  ws_.reach = -1.0;
  ws_.x_cover_known = false;
  ws_.nearby.clear();
  ws_.nearby_gap_at_q.clear();
  ws_.candidates.assign(ws_.nearby, ws_.nearby_gap_at_q);
}

// Candidate rows: those within reach of the largest displacement seen this step, found once
// and refreshed only if a later displacement outgrows the reach.
const RowStretches& Gvi::candidates_for(const System& system, const std::vector<Vec3>& x,
                                        double largest2_bound, bool exact,
                                        const std::vector<std::int32_t>* moved,
                                        const NearbyRows::StretchPass* then, bool* then_ran) {
  const std::vector<Vec3>& q = ws_.q;
  const double gap_tolerance = constraints_.tolerances.gap;
  ws_.nearby_refreshed = false;
  if (then_ran) *then_ran = false;
  // Inequality rows are hard-sphere pairs and walls: without either there is none to find
  // (ws_.nearby stays empty), and no displacement need be measured for them.
  if (!has_inequalities()) return ws_.candidates;
  if (particle_reaches()) {
    bool covered = false;
    if (ws_.reach < 0.0) {
      // No reaches yet this step.
    } else if (is_x(system, x) && ws_.x_cover_known) {
      covered = ws_.x_covered;  // found when x was made (displaced())
    } else if (&x == &ws_.predicted && moved == &ws_.changed_particles && ws_.changed_cover_known) {
      covered = ws_.changed_covered;  // found by the threads that reflected them
    } else {
      covered = reaches_cover(x, moved);
    }
    if (!covered) {
      const bool ran = collect_by_particle_reach(system, x, then);
      if (then_ran) *then_ran = ran;
    }
    return ws_.candidates;
  }
  // 2 sqrt(s) + tol is monotone in s (each operation correctly rounded): a bound that shows
  // no refresh due shows what the exact largest would.
  if (largest2_bound >= 0.0 && 2.0 * std::sqrt(largest2_bound) + gap_tolerance <= ws_.reach) {
    ws_.largest2 = largest2_bound;
    return ws_.candidates;
  }
  // The largest |x - q| as the square root of the largest square: the same number (the
  // square root is monotone and correctly rounded), one root instead of one per particle.
  double largest2 = 0.0;
  if (exact) {
    largest2 = largest2_bound;
  } else {
    largest2 = ordered_max(q.size(), 0.0, [&](std::size_t i) { return norm2(x[i] - q[i]); });
  }
  ws_.largest2 = largest2;
  const double largest = std::sqrt(largest2);
  if (2.0 * largest + gap_tolerance > ws_.reach) {
    ws_.reach = 4.0 * largest + 2.0 * gap_tolerance;
    if (constraints_.linearized) {
      ws_.nearby =
          constraints_.nearby_inequalities(system.particles, q.data(), engine_.neighbors(),
                                           system.box, ws_.reach, previous_positions_.data());
      ws_.nearby_gap_at_q.resize(ws_.nearby.size());
      for (std::size_t k = 0; k < ws_.nearby.size(); ++k) {
        ws_.nearby_gap_at_q[k] = evaluate(ws_.nearby[k], q.data(), system.box).gap;
      }
    } else {
      nearby_rows_.collect(constraints_, system.particles, q.data(), engine_.neighbors(),
                           system.box, ws_.reach, nullptr, gap_tolerance, ws_.nearby,
                           ws_.nearby_gap_at_q);
    }
    ws_.candidates.assign(ws_.nearby, ws_.nearby_gap_at_q);
    ws_.nearby_refreshed = true;
  }
  return ws_.candidates;
}

bool Gvi::is_x(const System& system, const std::vector<Vec3>& v) const {
  return &v == &x_now(system);
}

const std::vector<Vec3>& Gvi::x_now(const System& system) const {
  return ws_.x_in_positions ? system.particles.position : ws_.x;
}

bool Gvi::has_inequalities() const {
  return constraints_.hard_spheres || !constraints_.walls.empty();
}

bool Gvi::particle_reaches() const {
  return contact_ != ContactTreatment::impact_time && !constraints_.linearized &&
         (constraints_.hard_spheres || !constraints_.walls.empty());
}

// Whether every particle's displacement to x (or, given `moved`, that of each particle in it,
// the others' being unchanged since the last check) is within its reach less half the gap
// tolerance: then each pair's two displacements and the tolerance fit in the pair's reach.
bool Gvi::reaches_cover(const std::vector<Vec3>& x, const std::vector<std::int32_t>* moved) const {
  const Vec3* at = x.data();
  const Vec3* q = ws_.q.data();
  const double* limit2 = ws_.reach_limit2.data();
  if (moved) {
    for (const std::int32_t i : *moved) {
      if (!(norm2(at[i] - q[i]) <= limit2[i])) return false;
    }
    return true;
  }
  // Without a branch per particle (none is expected to fail): a count of failures.
  const int chunks = chunks_for_cheap(x.size());
  ChunkSlots<std::size_t> outgrown(static_cast<std::size_t>(chunks));
  for_each_chunk(x.size(), chunks, [&](int c, std::size_t begin, std::size_t end) {
    std::size_t count = 0;
    for (std::size_t i = begin; i < end; ++i) count += !(norm2(at[i] - q[i]) <= limit2[i]);
    outgrown[static_cast<std::size_t>(c)] = count;
  });
  for (const std::size_t count : outgrown) {
    if (count > 0) return false;
  }
  return true;
}

// Per particle, a reach of twice its displacement to x (at least kReachFloor times the
// largest, and never less than before this step) plus the gap tolerance: a pair is a
// candidate when its gap at q is within its two particles' reaches. Against one reach of
// four times the step's largest displacement for every pair, most pairs of slow particles
// drop out; a particle may then double its displacement (a reflection) before the rows
// are collected again.
bool Gvi::collect_by_particle_reach(const System& system, const std::vector<Vec3>& x,
                                    const NearbyRows::StretchPass* then) {
  const std::size_t n = ws_.q.size();
  const double gap_tolerance = constraints_.tolerances.gap;
  const bool first = ws_.reach < 0.0;
  ws_.displacement2.resize(n);
  ws_.reach_limit2.resize(n);
  ws_.particle_reach.resize(n);
  const Vec3* at = x.data();
  const Vec3* q = ws_.q.data();
  double* moved2 = ws_.displacement2.data();
  // Made with the prediction by start_step (a reflection since changes the prediction), and
  // the reaches with them (from the last step's floor: `folded`).
  const bool made = &x == &ws_.predicted && ws_.displacement2_of_prediction;
  const bool folded = made && first && ws_.reaches_of_prediction;
  const bool anchored = folded && ws_.anchored;
  ws_.displacement2_of_prediction = false;
  ws_.reaches_of_prediction = false;
  ws_.anchored = false;
  const double largest2 = made ? ws_.prediction_largest2 : ordered_max(n, 0.0, [&](std::size_t i) {
    moved2[i] = norm2(at[i] - q[i]);
    return moved2[i];
  });
  // The floor by its square: any floor serves (it only widens reaches), and the widest
  // reach is the largest displacement's or the floor's, taken the same way.
  const double floor = kReachFloor * std::sqrt(largest2);
  const double floor2 = folded ? ws_.reach_floor2 : floor * floor;
  if (first) ws_.reach_floor2 = floor * floor;
  double* reach = ws_.particle_reach.data();
  double* limit2 = ws_.reach_limit2.data();
  // As packets (std::sqrt, which may set errno, does not vectorise), chunk by chunk; the
  // step's first reaches grow from zero, set here by the thread that holds the lines. Made
  // in the collection's first pass over the particles (their own job a step, before).
  const RangePass make_reaches = [=](std::size_t begin, std::size_t end) {
    const auto length = static_cast<Eigen::Index>(end - begin);
    Eigen::Map<Eigen::ArrayXd> out(reach + begin, length), out_limit2(limit2 + begin, length);
    const Eigen::Map<const Eigen::ArrayXd> in(moved2 + begin, length);
    if (first) out.setZero();
    out = out.max(2.0 * in.max(floor2).sqrt() + gap_tolerance);
    out_limit2 = (out - 0.5 * gap_tolerance).square();
  };
  const double widest = 2.0 * std::sqrt(std::max(largest2, floor2)) + gap_tolerance;
  ws_.reach = first ? 2.0 * widest : std::max(ws_.reach, 2.0 * widest);
  ws_.changed_cover_known = false;
  // The reaches only grow: x stays covered if it was, and is when they were made from it.
  if (is_x(system, x)) ws_.x_cover_known = ws_.x_covered = true;
  if (ws_.x_cover_known && !ws_.x_covered) ws_.x_cover_known = false;
  const bool ran = nearby_rows_.collect(
      constraints_, system.particles, q, engine_.neighbors(), system.box, ws_.reach, reach,
      gap_tolerance, ws_.nearby, ws_.nearby_gap_at_q, folded ? nullptr : &make_reaches,
      &ws_.candidates, anchored ? &ws_.anchored_largest2 : nullptr, then);
  ws_.nearby_refreshed = true;
  return ran;
}

// Extended active set and reflection. A reflection can send a particle into a contact the
// first prediction did not see: predict again from the reflected momenta until the active
// set stops growing. After the first round only rows touching a particle whose prediction
// changed can join (the others' gaps at q and at the prediction are as they were), unless
// the candidates were refreshed: those rows alone are looked at again.
void Gvi::find_active_set(System& system) {
  const std::size_t n = system.particles.size();
  const double gap_tolerance = constraints_.tolerances.gap;
  std::vector<Constraint>& active = ws_.active;
  active.clear();
  ws_.active_gap_at_q.clear();
  if (!has_inequalities()) return;  // no row can be active
  // Without equality rows a Verlet prediction is the free step, particle by particle: after a
  // reflection only the reflected particles' predictions can change, and only theirs are
  // made again (the same numbers a whole prediction would give).
  const bool local_predictions =
      lagrangian_ == Lagrangian::verlet && constraints_.equalities.empty();
  const bool clear =
      local_predictions && ws_.prediction_changed_clear && ws_.prediction_changed.size() == n;
  ws_.prediction_changed_clear = false;
  ws_.prediction_changed.resize(n);
  const char initial = local_predictions ? 0 : 1;
  if (!clear) parallel_for(n, [&, initial](std::size_t i) { ws_.prediction_changed[i] = initial; });
  ws_.changed_particles.clear();
  bool settled = false;
  // After the first round: a bound on max |prediction - q|^2, from the last round's and the
  // particles whose prediction changed.
  double largest2_bound = -1.0;
  std::size_t reflected_rows = 0;  // the rows the last round reflected (the first of `active`)
  // The first round's test (no row is active yet) on the threads that collect the candidates,
  // right after each collects its stretch, in the collection's job: its own job and start a
  // step, before, and each stretch's rows read again there.
  // Whether a candidate not yet active joins: active at q (its gap) or overlapping at the
  // prediction. Every round's test.
  auto joins = [&, gap_tolerance](const Constraint& c, double gap) {
    return gap <= gap_tolerance ||
           gap_unless_beyond(c, ws_.predicted.data(), system.box, 0.0) <= 0.0;
  };
  ws_.stretch_passing.resize(static_cast<std::size_t>(thread_count()));
  const NearbyRows::StretchPass test_collected = [&](int stretch, const Constraint* rows,
                                                     const double* gaps, std::size_t count) {
    GviWorkspace::StretchPassing& passing =
        ws_.stretch_passing.at(static_cast<std::size_t>(stretch)).value;
    passing.index.clear();
    passing.rows.clear();
    passing.gaps.clear();
    for (std::size_t k = 0; k < count; ++k) {
      if (joins(rows[k], gaps[k])) {
        passing.index.push_back(static_cast<std::uint32_t>(k));
        passing.rows.push_back(rows[k]);
        passing.gaps.push_back(gaps[k]);
      }
    }
  };
  // A later round's test, where the last round's reflections ran in a job of the team: in
  // that job (its own job and start a round, before), once every prediction is made, unless
  // a reflected particle left its reach (then the candidates are collected again first).
  bool tested_in_reflections = false;
  int reflections_test_chunks = 1;
  for (int round = 0; round < constraints_.limits.active_set_rounds; ++round) {
    const bool tested_before = tested_in_reflections;
    tested_in_reflections = false;
    bool tested = false;
    const RowStretches& candidates =
        candidates_for(system, ws_.predicted, largest2_bound, false,
                       round > 0 && local_predictions ? &ws_.changed_particles : nullptr,
                       round == 0 ? &test_collected : nullptr, &tested);
    const bool every_row = round == 0 || ws_.nearby_refreshed;
    // Per candidate, whether it is in the active set already (the candidates are distinct
    // rows): made again by search when the candidates were refreshed.
    if (every_row) mark_contained(active, candidates, ws_.row_keys, ws_.candidate_active);
    bool grew = false;
    auto test_rows = [&](bool every_row, std::size_t begin, std::size_t end, auto&& pass) {
      candidates.for_each(begin, end, [&](std::size_t k, const Constraint& c, double gap) {
        if (!every_row && !ws_.prediction_changed[c.i] &&
            (c.j < 0 || !ws_.prediction_changed[c.j])) {
          return;
        }
        // Not yet active, and active at q or overlapping at the prediction.
        if (!ws_.candidate_active[k] && joins(c, gap)) pass(k);
      });
    };
    auto test = [&, every_row](std::size_t begin, std::size_t end, auto&& pass) {
      test_rows(every_row, begin, end, pass);
    };
    auto join = [&](std::size_t k) {
      active.push_back(candidates[k]), grew = true;
      ws_.active_gap_at_q.push_back(candidates.gap(k));
      ws_.candidate_active[k] = 1;
    };
    if (tested) {
      for (std::size_t s = 0; s < candidates.stretches(); ++s) {
        const std::size_t first = candidates.first_of(s);
        // The passing rows as their threads copied them, one run each: gathered here from
        // the stretches, one or two of the other core's lines a row, the join took 2.5-3x as
        // long (bench/README.md, "Stop 70").
        const GviWorkspace::StretchPassing& passing = ws_.stretch_passing[s].value;
        active.insert(active.end(), passing.rows.begin(), passing.rows.end());
        ws_.active_gap_at_q.insert(ws_.active_gap_at_q.end(), passing.gaps.begin(),
                                   passing.gaps.end());
        for (const std::uint32_t k : passing.index) ws_.candidate_active[first + k] = 1;
        grew = grew || !passing.index.empty();
      }
    } else if (tested_before && !ws_.nearby_refreshed) {
      join_kept(candidates.size(), reflections_test_chunks, ws_.candidate_passing,
                ws_.reflections_test_kept, join);
    } else {
      // Split as the pass that wrote the predictions was.
      filter_in_order_visiting(candidates.size(),
                               chunks_for_rows_of(system.particles.size(), candidates.size()),
                               ws_.candidate_passing, test, join);
    }
    if (!grew || !reflections_) {
      settled = true;
      break;
    }
    // Without equality rows the active rows are the rows: not copied.
    const std::vector<Constraint>* rows = &active;
    if (!constraints_.equalities.empty()) {
      rows = &equalities_and(active);
    }
    if (local_predictions) {
      // Each reflected particle's prediction made again on the thread that reflected it,
      // which holds its lines (timed as the reflections).
      const TimedPhase reflecting(Phase::reflections);
      const std::size_t count = candidates.size();
      const int chunks = chunks_for_rows_of(n, count);
      const bool next_round = round + 1 < constraints_.limits.active_set_rounds;
      const bool test_with = next_round && chunks > 1 && chunks == chunks_for_cheap(n);
      ChunkPass test_next;
      if (test_with) {
        ws_.candidate_passing.resize(count);
        ws_.reflections_test_kept.assign(static_cast<std::size_t>(chunks), 0);
        test_next = [&](int chunk, std::size_t begin, std::size_t end) {
          std::size_t at = begin;
          test_rows(false, begin, end, [&](std::size_t k) {
            ws_.candidate_passing[at++] = static_cast<std::uint32_t>(k);
          });
          ws_.reflections_test_kept[static_cast<std::size_t>(chunk)] = at - begin;
        };
      }
      // The next rounds in the same job while each finds rows and has a round after it for its
      // own test (test_with's condition): a job and the calling thread's work between two
      // rounds fewer each (hs_4000: two rounds of reflections a step, bench/README.md, "Stop
      // 73").
      int rounds_in_job = 0;
      FurtherRounds further;
      if (test_with) {
        further.follows = [&, round, chunks](int followed) {
          if (round + followed + 2 >= constraints_.limits.active_set_rounds) return false;
          for (std::size_t c = 0; c < static_cast<std::size_t>(chunks); ++c) {
            if (ws_.reflections_test_kept[c] > 0) return true;
          }
          return false;
        };
        further.start = [&, count, chunks] {
          ++rounds_in_job;
          join_kept(count, chunks, ws_.candidate_passing, ws_.reflections_test_kept, join);
        };
      }
      largest2_bound =
          reflect_and_predict(system, *rows, reflected_rows, test_with ? &test_next : nullptr,
                              count, &tested_in_reflections, test_with ? &further : nullptr);
      round += rounds_in_job;
      reflections_test_chunks = chunks;
      reflected_rows = rows->size();
      continue;
    }
    {
      const TimedPhase reflecting(Phase::reflections);
      reflect_clusters(system, *rows, constraints_.equalities.size(), ws_.q, ws_.p);
    }
    const TimedPhase predicting(Phase::prediction);
    std::swap(ws_.previous_prediction, ws_.predicted);
    predict(system, ws_.p, ws_.predicted, constrained_predictor_, true);
    largest2_bound = ordered_max(n, ws_.largest2, [&](std::size_t i) {
      const Vec3& a = ws_.predicted[i];
      const Vec3& b = ws_.previous_prediction[i];
      const bool changed = a.x != b.x || a.y != b.y || a.z != b.z;
      ws_.prediction_changed[i] = changed;
      if (!changed) return 0.0;
      return norm2(a - ws_.q[i]);
    });
  }
  if (local_predictions) {
    // The last round's marks (reflect_and_predict unmarks the earlier rounds').
    for (std::int32_t i : ws_.changed_particles) ws_.prediction_changed[i] = 0;
    ws_.prediction_changed_clear = true;
  }
  stats_.active += static_cast<std::int64_t>(active.size());
  if (!settled) ++stats_.active_set_caps;
}

// The active rows reflected, and the free Verlet prediction made again for their particles
// (the only ones reflections move), as free_displacement and predict make it: marks those
// whose prediction changed and returns the bound on max |prediction - q|^2.
double Gvi::reflect_and_predict(System& system, const std::vector<Constraint>& rows,
                                std::size_t first_new_row, const ChunkPass* next_test,
                                std::size_t test_count, bool* tested,
                                const FurtherRounds* further) {
  const Particles& P = system.particles;
  const double h = dt_;
  const std::vector<Vec3>& f = engine_.force();
  for (std::int32_t i : ws_.changed_particles) ws_.prediction_changed[i] = 0;
  ws_.changed_particles.clear();
  // Per share of the reflections: its changed particles and its bound.
  const auto shares = static_cast<std::size_t>(thread_count());
  ws_.changed_of_chunk.resize(shares);
  for (OnItsOwnLine<std::vector<std::int32_t>>& changed : ws_.changed_of_chunk) {
    changed.value.clear();
  }
  ws_.changed_tally.assign(
      shares, OnItsOwnLine<GviWorkspace::ChangedTally>{{ws_.largest2, std::size_t{0}}});
  // Each new prediction tested against its particle's reach where it is made, as
  // reaches_cover tests the moved particles (the reaches stay until the next round's test).
  const bool reaches_made =
      particle_reaches() && ws_.reach >= 0.0 && ws_.reach_limit2.size() == P.size();
  const double* limit2 = reaches_made ? ws_.reach_limit2.data() : nullptr;
  // The arrays by value: behind references they would be loaded again at every particle.
  const Vec3* p = ws_.p.data();
  const Vec3* force = f.data();
  const double* mass = P.mass.data();
  const Vec3* position = P.position.data();
  const Vec3* q = ws_.q.data();
  Vec3* predicted = ws_.predicted.data();
  char* changed = ws_.prediction_changed.data();
  const AfterReflection again = [&, h, p, force, mass, position, q, predicted, changed, limit2](
                                    int chunk, const std::int32_t* particles, std::size_t count) {
    const auto c = static_cast<std::size_t>(chunk);
    for (std::size_t k = 0; k < count; ++k) {
      const std::int32_t i = particles[k];
      const Vec3 next = position[i] + free_step(half_kicked(p[i], force[i], h), h, mass[i]);
      Vec3& now = predicted[i];
      if (next.x != now.x || next.y != now.y || next.z != now.z) {
        now = next;
        changed[i] = 1;
        ws_.changed_of_chunk[c].value.push_back(i);
        GviWorkspace::ChangedTally& tally = ws_.changed_tally[c].value;
        const double moved2 = norm2(next - q[i]);
        tally.largest2 = std::max(tally.largest2, moved2);
        if (limit2) tally.outgrown += !(moved2 <= limit2[i]) ? 1 : 0;
      }
    }
  };
  // The next round's test once every chunk has reflected, unless a chunk saw a prediction
  // leave its reach (as candidates_for will find from the tallies).
  ChunkPass test_if_covered;
  if (next_test) {
    test_if_covered = [&, limit2](int chunk, std::size_t begin, std::size_t end) {
      if (!limit2) return;
      for (const OnItsOwnLine<GviWorkspace::ChangedTally>& tally : ws_.changed_tally) {
        if (tally.value.outgrown > 0) return;
      }
      (*next_test)(chunk, begin, end);
    };
  }
  // A round follows in the job where the test ran; its start unmarks the particles the last
  // round changed (as above, for the next test), and each chunk's start empties its tally
  // (which follows() reads).
  FurtherRounds rounds;
  if (further && next_test) {
    rounds.follows = [&, limit2](int followed) {
      if (!limit2) return false;
      for (const OnItsOwnLine<GviWorkspace::ChangedTally>& tally : ws_.changed_tally) {
        if (tally.value.outgrown > 0) return false;
      }
      return further->follows(followed);
    };
    rounds.start = [&] {
      for (std::size_t c = 0; c < shares; ++c) {
        for (const std::int32_t i : ws_.changed_of_chunk[c].value) ws_.prediction_changed[i] = 0;
        ws_.changed_of_chunk[c].value.clear();
      }
      further->start();
    };
    rounds.start_chunk = [&](int chunk) {
      ws_.changed_tally[static_cast<std::size_t>(chunk)].value =
          GviWorkspace::ChangedTally{ws_.largest2, std::size_t{0}};
    };
  }
  const bool test_ran = reflect_clusters(system, rows, 0, ws_.q, ws_.p, &again, first_new_row,
                                         next_test ? &test_if_covered : nullptr, test_count,
                                         further && next_test ? &rounds : nullptr);
  double largest2_bound = ws_.largest2;
  ws_.changed_cover_known = limit2 != nullptr;
  ws_.changed_covered = true;
  for (std::size_t c = 0; c < shares; ++c) {
    const std::vector<std::int32_t>& of_chunk = ws_.changed_of_chunk[c].value;
    ws_.changed_particles.insert(ws_.changed_particles.end(), of_chunk.begin(), of_chunk.end());
    largest2_bound = std::max(largest2_bound, ws_.changed_tally[c].value.largest2);
    ws_.changed_covered = ws_.changed_covered && ws_.changed_tally[c].value.outgrown == 0;
  }
  if (tested) *tested = test_ran && ws_.changed_cover_known && ws_.changed_covered;
  return largest2_bound;
}

// Smooth set: active at q and tangent to the momenta after reflection.
void Gvi::find_smooth_set(const System& system) {
  const ConstraintTolerances& tol = constraints_.tolerances;
  ws_.smooth.clear();
  for (std::size_t k = 0; k < ws_.active.size(); ++k) {
    // Most rows are active by their overlap at the prediction, their gaps at q known to be
    // beyond the tolerance (an exact gap, or +infinity for one certainly beyond): those are
    // not evaluated again.
    if (std::abs(ws_.active_gap_at_q[k]) > tol.gap) continue;
    const Constraint& c = ws_.active[k];
    const ConstraintValue v = evaluate(c, ws_.q.data(), system.box);
    if (std::abs(v.gap) > tol.gap) continue;
    if (std::abs(normal_velocity(c, v.u, ws_.p, system.particles)) <= tol.velocity) {
      ws_.smooth.push_back(c);
    }
  }
  stats_.smooth += static_cast<std::int64_t>(ws_.smooth.size());
}

void Gvi::displaced(Particles& P, bool kick, const ChunkPass* then, std::size_t then_count) {
  const std::size_t n = P.size();
  const double h = dt_;
  ws_.x.resize(n);
  ws_.x_builds = engine_.neighbors().builds();
  // With reaches per particle made this step: in the same pass, whether x stays within them.
  const bool by_particle = particle_reaches() && ws_.reach >= 0.0;
  ws_.x_cover_known = by_particle;
  // ordered_max's chunks, each also counting the particles beyond their reach and those
  // beyond the neighbour list's (needs_rebuild's test per particle, which the force
  // evaluation at x then need not make in a pass of its own).
  const int chunks = chunks_for_cheap(n);
  std::vector<double>& largest2 = ws_.chunk_largest2;
  std::vector<std::size_t>& outgrown = ws_.chunk_outgrown;
  largest2.assign(static_cast<std::size_t>(chunks), 0.0);
  outgrown.assign(static_cast<std::size_t>(chunks), 0);
  std::vector<std::size_t>& unlisted = ws_.chunk_unlisted;
  unlisted.assign(static_cast<std::size_t>(chunks), 0);
  const NeighborList& list = engine_.neighbors();
  const bool built = list.built_for(n);
  const double* limit2 = by_particle ? ws_.reach_limit2.data() : nullptr;
  // x = q + (half + impulse) (h / m), in vectors.
  const gvi_passes::EndPositions pass = end_positions_pass(ws_, P, h, list, built, limit2);
  const std::vector<Vec3>& f_start = engine_.force();
  // No row held and no force (the hard-sphere fluid's usual step): the force at x is f_start's
  // zeros, and the momentum update's velocities are made here from the half kick just made
  // (update_momenta's pass of its own was a job of the team a step). Its momenta are not
  // stored: nothing reads them after the velocities, and a later round of the feasibility
  // guard starts from the step's momenta again, as update_momenta then writes every velocity.
  const bool make_velocities = kick && engine_.forces_stay(n);
  ws_.velocities_made = make_velocities;
  double* velocity = numbers(P.velocity);
  auto end_positions = [&, make_velocities, velocity](int c, std::size_t begin, std::size_t end) {
    if (kick) {
      gvi_passes::half_kick(h, numbers(ws_.p), numbers(f_start), P.mass.data(), numbers(ws_.half),
                            nullptr, begin, end);
    }
    const gvi_passes::EndPositionsTally tally = gvi_passes::end_positions(pass, begin, end);
    if (make_velocities) {
      gvi_passes::kicked_velocities(h, numbers(ws_.half), pass.impulse, numbers(f_start),
                                    P.mass.data(), velocity, begin, end);
    }
    largest2[static_cast<std::size_t>(c)] = tally.largest2;
    outgrown[static_cast<std::size_t>(c)] = tally.beyond_reach;
    unlisted[static_cast<std::size_t>(c)] = tally.beyond_list;
  };
  if (then) {
    for_each_chunk_then(n, then_count, chunks, end_positions, *then);
  } else {
    for_each_chunk(n, chunks, end_positions);
  }
  ws_.x_largest2 = 0.0;
  ws_.x_covered = by_particle;
  ws_.x_listed = built;
  for (int c = 0; c < chunks; ++c) {
    ws_.x_largest2 = std::max(ws_.x_largest2, largest2[static_cast<std::size_t>(c)]);
    ws_.x_covered = ws_.x_covered && outgrown[static_cast<std::size_t>(c)] == 0;
    ws_.x_listed = ws_.x_listed && unlisted[static_cast<std::size_t>(c)] == 0;
  }
}

// ws_.rows as the equality rows, which never change, followed by `others`: the equalities
// (the default input's 1170 rods, 90 KB) are copied in only once, the rows after them replaced
// at each call (copied whole, 3 % of the calling thread's time on two threads).
const std::vector<Constraint>& Gvi::equalities_and(const std::vector<Constraint>& others) {
  if (ws_.rows_start_with_equalities) {
    ws_.rows.resize(constraints_.equalities.size());
  } else {
    ws_.rows = constraints_.equalities;
    ws_.rows_start_with_equalities = true;
  }
  ws_.rows.insert(ws_.rows.end(), others.begin(), others.end());
  return ws_.rows;
}

// Momenta before the new forces: half = p + h/2 F_start, positions q + h M^-1 (half +
// impulse), with F_start = F(q) (Verlet) or F at the step's midpoint (midpoint, by fixed
// point around the constrained solve).
bool Gvi::solve_held_positions(System& system) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  // The equality rows alone are passed as themselves: their clusters are prepared.
  if (!ws_.held.empty()) equalities_and(ws_.held);
  const std::vector<Constraint>& rows = ws_.held.empty() ? constraints_.equalities : ws_.rows;
  ws_.equality.assign(rows.size(), false);
  std::fill_n(ws_.equality.begin(), constraints_.equalities.size(), true);
  const std::vector<Vec3>& f_start = engine_.force();
  ws_.half.resize(n);
  // Verlet solves once: the free step and the zeroed impulses made in the half kick's pass;
  // the solve writes every impulse itself when every particle is in a rod's cluster.
  const bool once = lagrangian_ == Lagrangian::verlet && !rows.empty();
  if (once && ws_.half_kicked) {
    // Made by start_step from these momenta (rods alone: no reflection changed them).
  } else if (once) {
    ws_.free.resize(n);
    ws_.impulse.resize(n);
    const bool zero = !equalities_hold_every_particle(P);
    for_each_chunk(n, chunks_for_cheap(n), [&, h, zero](int, std::size_t begin, std::size_t end) {
      gvi_passes::half_kick(h, numbers(ws_.p), numbers(f_start), P.mass.data(), numbers(ws_.half),
                            numbers(ws_.free), begin, end);
      if (zero) std::fill(ws_.impulse.begin() + begin, ws_.impulse.begin() + end, Vec3{});
    });
  } else if (lagrangian_ == Lagrangian::verlet && rows.empty()) {
    // No row held (a hard-sphere fluid's usual step): the half kick in the end positions'
    // pass, one job of the team rather than two.
    ws_.impulse.clear();
    return true;
  } else {
    for_each_chunk(n, chunks_for_cheap(n), [&, h](int, std::size_t begin, std::size_t end) {
      gvi_passes::half_kick(h, numbers(ws_.p), numbers(f_start), P.mass.data(), numbers(ws_.half),
                            nullptr, begin, end);
    });
  }
  // Verlet: the free step is the constrained predictor's last one (the same numbers from
  // the same momenta and forces) at the same q, so a chain no contact row joins, whose
  // free step is bit for bit the one predicted, takes the prediction's impulses.
  const bool predicted = lagrangian_ == Lagrangian::verlet && constrained_predictor_ &&
                         ws_.kicked_displacement.size() == n && ws_.prediction_kick.size() == n;
  const SolvedEqualities prediction{ws_.kicked_displacement, ws_.prediction_kick};
  auto solve = [&] {
    // No rows held (a hard-sphere fluid's usual step): every impulse is zero, not stored.
    if (rows.empty()) {
      ws_.impulse.clear();
      return;
    }
    if (!once) {
      ws_.impulse.assign(n, Vec3{});
      ws_.free.resize(n);
      parallel_for(n, [&, h](std::size_t i) { ws_.free[i] = ws_.half[i] * (h / P.mass[i]); });
    }
    ws_.position_virial = solve_positions(system, rows, ws_.equality, ws_.q, ws_.free, ws_.impulse,
                                          nullptr, predicted ? &prediction : nullptr);
  };
  if (lagrangian_ == Lagrangian::verlet) {
    solve();
    return false;
  }
  iterate_midpoint(system, 1, [&] {
    solve();
    displaced(system.particles);
    ws_.mid.resize(n);
    parallel_for(n, [&](std::size_t i) { ws_.mid[i] = (ws_.q[i] + ws_.x[i]) * 0.5; });
    engine_.forces_at(system, ws_.mid, ws_.f_mid);
    return ordered_max(n, 0.0, [&, h](std::size_t i) {
      const Vec3 next = half_kicked(ws_.p[i], ws_.f_mid[i], h);
      const double change = norm(next - ws_.half[i]) * h / P.mass[i];
      ws_.half[i] = next;
      return change;
    });
  });
  return false;
}

// On one thread the passes over every particle are as fast (measured on the rigid melt:
// contiguous loops the compiler vectorises); on two the clusters' passes keep each
// thread's particles in its own cache and open no region of their own (position update
// 0.107-0.115 -> 0.065-0.073 s per 1000 steps).
bool Gvi::steps_by_cluster(const Particles& particles) {
  return thread_count() > 1 && lagrangian_ == Lagrangian::verlet && !has_inequalities() &&
         !constrained_predictor_ && !constraints_.equalities.empty() &&
         equalities_hold_every_particle(particles);
}

// On the thread that solves the clusters: their particles' half kicks and free steps are made
// just before, their end positions just after, and the two passes over every particle (two
// parallel regions) are gone. The largest displacement is exact in any order, and the list's
// test at x is counted per chunk, as displaced() makes them.
void Gvi::held_positions_by_cluster(System& system) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  const std::vector<Vec3>& f = engine_.force();
  ws_.half.resize(n);
  ws_.free.resize(n);
  ws_.impulse.resize(n);  // every one written by the solves
  ws_.x.resize(n);
  ws_.equality.assign(constraints_.equalities.size(), true);
  const auto slots = static_cast<std::size_t>(thread_count());
  ws_.chunk_largest2.assign(slots, 0.0);
  ws_.chunk_unlisted.assign(slots, 0);
  const NeighborList& list = engine_.neighbors();
  const bool built = list.built_for(n);
  ClusterPasses passes;
  // q, the momenta's half kick and the free step, made from the velocities (start_step made
  // none of them).
  gvi_passes::StepStart start = step_start_pass(ws_, P, h, f);
  start.half = numbers(ws_.half);
  start.free = numbers(ws_.free);
  passes.before = [&](int, const ParticleRun& run) {
    run.for_each_range(
        [&](std::size_t begin, std::size_t end) { gvi_passes::step_start(start, begin, end); });
  };
  // x = q + (half + impulse) (h / m), in vectors.
  const gvi_passes::EndPositions end_pass = end_positions_pass(ws_, P, h, list, built, nullptr);
  passes.after = [&](int chunk, const ParticleRun& run) {
    const auto c = static_cast<std::size_t>(chunk);
    run.for_each_range([&](std::size_t begin, std::size_t end) {
      const gvi_passes::EndPositionsTally tally = gvi_passes::end_positions(end_pass, begin, end);
      ws_.chunk_largest2[c] = std::max(ws_.chunk_largest2[c], tally.largest2);
      ws_.chunk_unlisted[c] += tally.beyond_list;
    });
  };
  ws_.position_virial = solve_positions(system, constraints_.equalities, ws_.equality, ws_.q,
                                        ws_.free, ws_.impulse, nullptr, nullptr, &passes);
  ws_.x_builds = list.builds();
  ws_.x_cover_known = false;
  ws_.x_largest2 = 0.0;
  ws_.x_listed = built;
  for (std::size_t c = 0; c < slots; ++c) {
    ws_.x_largest2 = std::max(ws_.x_largest2, ws_.chunk_largest2[c]);
    ws_.x_listed = ws_.x_listed && ws_.chunk_unlisted[c] == 0;
  }
}

// Position update, then the feasibility guard: inequality rows that would still end the step
// overlapped join the complementarity set and the step is solved again.
void Gvi::update_positions(System& system) {
  const double gap_tolerance = constraints_.tolerances.gap;
  ws_.position_virial = 0.0;
  // DSI: no reflections; every row of the extended active set is a complementarity row.
  ws_.held = reflections_ ? ws_.smooth : ws_.active;
  ws_.landed.clear();  // rows added by the guard this step
  const bool by_cluster = steps_by_cluster(system.particles);
  const std::size_t n = system.particles.size();
  for (int round = 0;; ++round) {
    ws_.violated.clear();
    ws_.x_smallest_gap_known = false;
    // Overlapping beyond tolerance at x (such a row is also active there). The same pass
    // keeps the smallest candidate gap at x for the constraint checks: every gap that may
    // be below the smallest so far (or the tolerance) exactly, the others beyond both. Per
    // chunk of candidates, each bounded by its own running minimum: the exact minimum and
    // the serial order of the overlapping rows on any number of threads. Split as the pass
    // that wrote x was. Each chunk keeps its overlapping rows at the start of its stretch of
    // `passing`: the calling thread reads those alone, not a flag per row.
    const bool guarded = feasibility_ != Feasibility::none;
    const RowStretches* candidates = &ws_.candidates;
    std::size_t count = candidates->size();
    int chunks = chunks_for_rows_of(n, count);
    std::vector<std::uint32_t>& passing = ws_.candidate_passing;
    ChunkSlots<double> chunk_smallest(static_cast<std::size_t>(chunks));
    ChunkSlots<std::size_t> kept(static_cast<std::size_t>(chunks));
    auto screen_at_x = [&, gap_tolerance](int chunk, std::size_t begin, std::size_t end) {
      double smallest = std::numeric_limits<double>::infinity();
      std::size_t at = begin;
      candidates->for_each(begin, end, [&](std::size_t k, const Constraint& c, double) {
        const double gap =
            gap_unless_beyond(c, ws_.x.data(), system.box, std::max(smallest, -gap_tolerance));
        smallest = std::min(smallest, gap);
        if (gap < -gap_tolerance) passing[at++] = static_cast<std::uint32_t>(k);
      });
      chunk_smallest[static_cast<std::size_t>(chunk)] = smallest;
      kept[static_cast<std::size_t>(chunk)] = at - begin;
    };
    // With reaches per particle made this step, the candidates stay unless x leaves them,
    // which the end positions' chunks count: the screen then runs in their job, after them
    // (a job and its start fewer a step), where every chunk counted none.
    bool screened = false;
    const ChunkPass screen_if_covered = [&](int chunk, std::size_t begin, std::size_t end) {
      for (const std::size_t outgrown : ws_.chunk_outgrown) {
        if (outgrown > 0) return;
      }
      if (chunk == 0) screened = true;
      screen_at_x(chunk, begin, end);
    };
    const bool screen_with_x = guarded && !by_cluster && particle_reaches() && ws_.reach >= 0.0 &&
                               chunks > 1 && chunks == chunks_for_cheap(n);
    if (screen_with_x) passing.resize(count);
    if (by_cluster) {
      held_positions_by_cluster(system);
    } else {
      const bool kick = solve_held_positions(system);
      displaced(system.particles, kick, screen_with_x ? &screen_if_covered : nullptr, count);
    }
    if (guarded) {
      candidates = &candidates_for(system, ws_.x, ws_.x_largest2, true);
      if (!screened || ws_.nearby_refreshed) {
        count = candidates->size();
        chunks = chunks_for_rows_of(n, count);
        passing.resize(count);
        chunk_smallest = ChunkSlots<double>(static_cast<std::size_t>(chunks));
        kept = ChunkSlots<std::size_t>(static_cast<std::size_t>(chunks));
        for_each_chunk(count, chunks, screen_at_x);
      }
      double smallest = std::numeric_limits<double>::infinity();
      for (const double s : chunk_smallest) smallest = std::min(smallest, s);
      join_kept(count, chunks, passing, kept, [&](std::size_t k) {
        if (!contains(ws_.held, (*candidates)[k])) ws_.violated.push_back((*candidates)[k]);
      });
      ws_.x_smallest_gap = smallest;
      ws_.x_smallest_gap_known = true;
    }
    if (ws_.violated.empty()) break;
    if (round == constraints_.limits.feasibility_rounds) {
      ++stats_.feasibility_caps;
      break;
    }
    ws_.held.insert(ws_.held.end(), ws_.violated.begin(), ws_.violated.end());
    ws_.landed.insert(ws_.landed.end(), ws_.violated.begin(), ws_.violated.end());
  }
  stats_.fallbacks += static_cast<std::int64_t>(ws_.landed.size());
}

// H at the start of the step (the list is valid at q, so this evaluation neither rebuilds
// nor wraps). Evaluated here even when the last step's end tallied the potential at these
// positions: that tally may have summed over the list before a rebuild, in another order,
// and only thermo steps tally, so reusing it made the trajectory depend on the thermo
// interval (in the last bits, then chaotically).
double Gvi::start_energy(System& system) {
  const Particles& P = system.particles;
  const double potential = engine_.compute(system, true).potential;
  double energy = potential;
  for (std::size_t i = 0; i < P.size(); ++i) energy += 0.5 * norm2(ws_.p_start[i]) / P.mass[i];
  return energy;
}

// Momentum update: p + h/2 (F(q) + F(x)) + impulse, projected onto the equality rows and the
// held rows still active at x (a landed row too, when the guard is inelastic).
void Gvi::update_momenta(System& system, bool tally) {
  Particles& P = system.particles;
  const std::size_t n = P.size();
  const double h = dt_;
  std::vector<Vec3>& p = ws_.p;
  const bool landed = !ws_.landed.empty();
  const double target_energy =
      feasibility_ == Feasibility::restore && landed ? start_energy(system) : 0.0;
  // x's buffer becomes the positions' and the old positions' buffer the next x (the next
  // step makes it anew), instead of a copy: the checks after this read x there.
  std::swap(P.position, ws_.x);
  ws_.x_in_positions = true;
  system.step += 1;
  system.time += h;
  // The list's test at x may be known from displaced() (no rebuild since x was made).
  const bool listed = ws_.x_listed && ws_.x_builds == engine_.neighbors().builds();
  engine_.compute(system, tally || (feasibility_ == Feasibility::restore && landed), listed);
  // The second half kick: F(x) for Verlet, the midpoint force again for midpoint, added to
  // the momenta before the forces, half + impulse (made here: nothing reads them earlier).
  const std::vector<Vec3>& f = lagrangian_ == Lagrangian::verlet ? engine_.force() : ws_.f_mid;
  if (steps_by_cluster(P)) {
    // The kick before a chunk's projections, the velocities after, on their thread (the
    // held rows are the rods alone, and nothing lands).
    ClusterPasses passes;
    passes.before = [&, h](int, const ParticleRun& run) {
      run.for_each_range([&, h](std::size_t begin, std::size_t end) {
        gvi_passes::second_kick(h, numbers(ws_.half), numbers(ws_.impulse), numbers(f), numbers(p),
                                begin, end);
      });
    };
    passes.after = [&](int, const ParticleRun& run) {
      run.for_each_range([&](std::size_t begin, std::size_t end) {
        gvi_passes::velocities(numbers(p), P.mass.data(), numbers(P.velocity), begin, end);
      });
    };
    step_virial_ += project_momenta(system, constraints_.equalities, P.position, p, &passes);
    step_virial_ += ws_.position_virial;
    return;
  }
  // momentum = half + impulse; momentum += f (0.5 h), in vectors.
  const double* impulse = held_impulses(ws_);
  // No row to project the momenta on, none landed (the hard-sphere fluid's usual step): the
  // velocities in the kick's pass, one job of the team rather than two.
  const bool kick_alone = ws_.held.empty() && constraints_.equalities.empty() && !landed;
  // The end positions' pass made the velocities from these numbers (it made them only for
  // Verlet without force, and compute() above left f_start's zeros), and nothing reads the
  // momenta after them.
  const bool made = kick_alone && ws_.velocities_made;
  ws_.velocities_made = false;
  if (!made) {
    for_each_chunk(n, chunks_for_cheap(n), [&, h](int, std::size_t begin, std::size_t end) {
      gvi_passes::second_kick(h, numbers(ws_.half), impulse, numbers(f), numbers(p), begin, end);
      if (kick_alone) {
        gvi_passes::velocities(numbers(p), P.mass.data(), numbers(P.velocity), begin, end);
      }
    });
  }
  if (kick_alone) {
    ws_.momentum_rows.clear();
    step_virial_ += ws_.position_virial;
    return;
  }
  const bool elastic = feasibility_ == Feasibility::reflect || feasibility_ == Feasibility::restore;
  ws_.momentum_rows.clear();
  for (const Constraint& c : ws_.held) {
    const bool elastic_landing = elastic && contains(ws_.landed, c);
    const double gap = evaluate(c, P.position.data(), system.box).gap;
    if (!elastic_landing && std::abs(gap) <= constraints_.tolerances.gap) {
      ws_.momentum_rows.push_back(c);
    }
  }
  if (ws_.momentum_rows.empty()) {
    // The equality rows alone, passed as themselves: their clusters are prepared.
    if (!constraints_.equalities.empty()) {
      step_virial_ += project_momenta(system, constraints_.equalities, P.position, p);
    }
  } else {
    step_virial_ += project_momenta(system, equalities_and(ws_.momentum_rows), P.position, p);
  }
  step_virial_ += ws_.position_virial;
  if (elastic && landed) {
    // The landed rows now touch: reflect the momenta that still approach them, at x.
    const std::vector<Constraint>& rows = equalities_and(ws_.landed);
    const TimedPhase reflecting(Phase::reflections);
    reflect_clusters(system, rows, constraints_.equalities.size(), P.position, p);
  }
  if (feasibility_ == Feasibility::restore && landed) {
    restore_energy(system, ws_.landed, target_energy, p);
  }
  for_each_chunk(n, chunks_for_cheap(n), [&](int, std::size_t begin, std::size_t end) {
    gvi_passes::velocities(numbers(p), P.mass.data(), numbers(P.velocity), begin, end);
  });
}

// The rows that can have closed this step are among the candidates (their reach covers the
// step's displacements): they decide overlaps; the exact minimum over every pair is taken on
// thermo steps, where it is reported.
void Gvi::check_constraints(const System& system, bool tally) {
  // The positions are x unless the force evaluation rebuilt the neighbour list, which
  // wraps them.
  const bool at_x = engine_.neighbors().builds() == ws_.x_builds;
  if (!at_x) ws_.x_in_positions = false;
  if (at_x) {
    // x: the same positions, whose cover by the reaches is known.
    candidates_for(system, x_now(system), ws_.x_largest2, true);
  } else {
    candidates_for(system, system.particles.position);
  }
  // The feasibility guard's last pass saw the same candidates at the same positions.
  const bool known = at_x && ws_.x_smallest_gap_known && !ws_.nearby_refreshed;
  ws_.x_smallest_gap_known = false;
  // Nothing moves the positions after the momentum update's projection. Unless known, the
  // candidates are read as one vector.
  const std::vector<Constraint>* candidates = &ws_.nearby;
  if (!known && ws_.candidates.stretches() > 1) {
    ws_.candidates.join(ws_.joined, ws_.joined_gaps);
    candidates = &ws_.joined;
  }
  record_geometry(system, *candidates, tally, known ? &ws_.x_smallest_gap : nullptr, true);
}

void Gvi::restore_energy(System& system, const std::vector<Constraint>& landed, double target,
                         std::vector<Vec3>& p, std::optional<double> shadow_target) {
  const Particles& P = system.particles;
  const std::size_t n = P.size();
  // Direction: the sum of the landed rows' normals at x, projected onto the rod manifold's
  // cotangent space so that the momenta stay tangent to it.
  std::vector<Vec3> d(n);
  std::vector<Constraint> rows = constraints_.equalities;
  rows.insert(rows.end(), landed.begin(), landed.end());
  const auto first_landed = static_cast<std::int32_t>(constraints_.equalities.size());
  for (const Cluster& cluster : find_clusters(rows, n)) {
    if (cluster.rows.back() < first_landed) continue;
    const LocalCluster local = localize(cluster, rows, P.mass);
    std::vector<bool> equality;
    for (std::int32_t r : cluster.rows) equality.push_back(r < first_landed);
    const Eigen::MatrixXd N =
        projected_normals(local, equality, gather(P.position, cluster.particles), system.box);
    const std::vector<Vec3> sum = unflatten(N.rowwise().sum());
    for (std::size_t k = 0; k < cluster.particles.size(); ++k) d[cluster.particles[k]] += sum[k];
  }
  // E(p + alpha d) = target: E(p) + b alpha + a/2 alpha^2 = E(p) + missing, E the shadow
  // energy where its own dependence on alpha keeps the quadratic convex (then taken with the
  // restored momenta themselves), else H. The larger root, or none where there is no real one.
  struct Along {
    double a = 0, b = 0, missing = 0;
    std::optional<double> root() const {
      const double discriminant = b * b + 2.0 * a * missing;
      if (discriminant < 0) return std::nullopt;
      return (-b + std::sqrt(discriminant)) / a;
    }
  };
  auto along = [&](const std::vector<Vec3>& direction) {
    double kinetic = 0;
    Along q;
    for (std::size_t i = 0; i < n; ++i) {
      kinetic += 0.5 * norm2(p[i]) / P.mass[i];
      q.a += norm2(direction[i]) / P.mass[i];
      q.b += dot(direction[i], p[i]) / P.mass[i];
    }
    q.missing = target - (kinetic + engine_.last().potential);
    if (!(q.a > 0) || !shadow_target) return q;
    const auto s = shadow_correction_on_rods(
        engine_, system, dt_, p, direction, constraints_.equalities, [&](std::vector<Vec3>& force) {
          project_momenta(system, constraints_.equalities, P.position, force);
        });
    if (s && q.a + 2.0 * s->quadratic > 0) {
      q.missing = *shadow_target - (kinetic + engine_.last().potential + s->constant);
      q.a += 2.0 * s->quadratic;
      q.b += s->linear;
    }
    return q;
  };
  const Along normal = along(d);
  if (!(normal.a > 0)) return;
  if (const std::optional<double> alpha = normal.root()) {
    for (std::size_t i = 0; i < n; ++i) p[i] += d[i] * *alpha;
    return;
  }
  // The energy to take away exceeds what the normal motion holds (several contacts in one
  // step on LJ's steep wall can end it with a potential energy far above the start's). With
  // impact_time it is taken from the motion relative to the rigid motion (momenta, angular
  // momentum and rods kept) of the touched rows' particles and their rod clusters, or where
  // that holds too little (two beads: their normal motion alone), of all particles.
  if (contact_ == ContactTreatment::impact_time) {
    std::vector<char> group = contact_group(landed, constraints_.equalities, n);
    for (int widened = 0; widened < 2; ++widened) {
      if (widened == 1) {
        if (std::all_of(group.begin(), group.end(), [](char in) { return in != 0; })) break;
        group.assign(n, 1);
      }
      const std::vector<Vec3> internal = internal_momenta(P, system.box, p, group);
      const Along relative = along(internal);
      const std::optional<double> alpha = relative.a > 0 ? relative.root() : std::nullopt;
      if (alpha) {
        for (std::size_t i = 0; i < n; ++i) p[i] += internal[i] * *alpha;
        ++stats_.relative_restorations;
        return;
      }
    }
  }
  // Out of reach: the normal motion stopped, the rest left.
  ++stats_.deficits;
  const double alpha = -normal.b / normal.a;
  for (std::size_t i = 0; i < n; ++i) p[i] += d[i] * alpha;
}

}  // namespace deli
