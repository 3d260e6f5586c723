#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "constraints/constraint.hpp"
#include "constraints/row_stretches.hpp"
#include "core/cache_line.hpp"
#include "core/vec3.hpp"

namespace deli {

// What one GVI step computes, kept from step to step so that no per-particle vector is
// allocated per step; each phase of Gvi::step reads and writes named parts of it.
struct GviWorkspace {
  // Prediction.
  std::vector<Vec3> p;                                 // momenta being updated (reflections, kicks)
  std::vector<Vec3> q;                                 // positions at the start of the step
  std::vector<Vec3> p_start;                           // start momenta, where read (start_step)
  std::vector<Vec3> predicted;                         // where the step would end unconstrained
  std::vector<Vec3> displacement;                      // the unconstrained step's, predict()'s
  std::vector<Vec3> prediction_kick;                   // the constrained predictor's impulses
  std::vector<Vec3> kicked_displacement;               // the free step they were solved for
  std::vector<char> displacement_changed;              // per particle, since that solve
  std::vector<Vec3> prediction_force, prediction_mid;  // midpoint predictor's fixed point
  std::vector<bool> all_equality;                      // one `true` per equality row

  // Candidate inequality rows near q, with their gaps at q (refreshed when a displacement
  // outgrows `reach`); a gap well beyond the gap tolerance may be held as +infinity. Read
  // through `candidates`: `nearby` holds its first stretch, every row but where the
  // collection by particle reach left its chunks' rows where their threads wrote them
  // (borrowed from Gvi::nearby_rows_ until its next collection).
  std::vector<Constraint> nearby;
  std::vector<double> nearby_gap_at_q;
  RowStretches candidates;
  std::vector<Constraint> joined;  // the candidates in one vector, for whole-vector readers
  std::vector<double> joined_gaps;
  double reach = -1.0;
  bool nearby_refreshed = false;  // by the last candidates call
  double largest2 = 0.0;          // its bound on max |x - q|^2 (exact when it refreshed)
  // By particle reach (Gvi::collect_by_particle_reach): each particle's reach, the squared
  // displacement it may reach before the rows are collected again, and |x - q|^2 of the
  // last collection.
  std::vector<double> particle_reach, reach_limit2, displacement2;
  // displacement2 holds |prediction - q|^2 as start_step's pass made them, with their largest
  // (until the prediction or q changes: the first collection of the step reads them).
  bool displacement2_of_prediction = false;
  double prediction_largest2 = 0.0;
  // The floor of the reaches the step's first collection made (its square; negative: none
  // yet). The next step's pass makes its first reaches with the prediction from this floor,
  // and with them each particle's displacement from the short list's anchors (`anchored`),
  // the largest squared anchored_largest2: then that collection runs no pass of its own.
  // Any floor serves (it only widens reaches); the last step's is close to the step's own.
  double reach_floor2 = -1.0;
  bool reaches_of_prediction = false;  // with displacement2_of_prediction
  bool anchored = false;
  double anchored_largest2 = 0.0;

  // Active and smooth sets; particles whose prediction changed in the last round.
  std::vector<Constraint> active, smooth;
  std::vector<double> active_gap_at_q;  // each active row's nearby_gap_at_q
  std::vector<Vec3> previous_prediction;
  std::vector<char> prediction_changed;
  std::vector<std::int32_t> changed_particles;  // those marked in prediction_changed
  // prediction_changed holds zeros alone (local predictions unmark their particles at the
  // end of the search): the next search need not clear it in a pass of its own.
  bool prediction_changed_clear = false;
  // The first round's candidates that pass its test, by stretch of the candidates (tested by
  // the threads that collected them): their indices within their stretch, and copies of their
  // rows and gaps, made there, for the join.
  struct StretchPassing {
    std::vector<std::uint32_t> index;
    std::vector<Constraint> rows;
    std::vector<double> gaps;
  };
  std::vector<OnItsOwnLine<StretchPassing>> stretch_passing;
  // A later round's passing candidates, tested in the last round's reflections' job: by chunk
  // of the candidates, at the start of its stretch of candidate_passing, this many.
  std::vector<std::size_t> reflections_test_kept;
  // By share of the reflections: the particles whose prediction changed, the bound on their
  // max |prediction - q|^2, and how many of them left their reach (reach_limit2).
  struct ChangedTally {
    double largest2 = 0.0;
    std::size_t outgrown = 0;
  };
  std::vector<OnItsOwnLine<std::vector<std::int32_t>>> changed_of_chunk;
  std::vector<OnItsOwnLine<ChangedTally>> changed_tally;
  // Whether changed_particles' predictions all lie within the particles' reaches, found by
  // the threads that made them (reflect_and_predict), for the search's next round.
  bool changed_cover_known = false;
  bool changed_covered = false;
  std::vector<char> candidate_active;  // per candidate row: in the active set
  // The candidate rows that passed a threaded test, at the start of each chunk's stretch.
  std::vector<std::uint32_t> candidate_passing;
  std::vector<std::pair<std::uint64_t, std::int32_t>> row_keys;  // mark_contained's scratch
  // The equality rows followed by some inequality rows (Gvi::equalities_and writes it).
  std::vector<Constraint> rows;
  bool rows_start_with_equalities = false;

  // Position update: half kick, impulses, end positions; rows held as complementarity rows
  // and those the feasibility guard landed.
  std::vector<Vec3> half, impulse, x, free, mid, f_mid;
  // half, free (and zeroed impulses) made by start_step from this step's momenta (Verlet,
  // rods alone, not by cluster), as solve_held_positions makes them.
  bool half_kicked = false;
  // This step's end positions are in the particles' positions, not x: the momentum update
  // swapped the two, and no list rebuild has wrapped them since.
  bool x_in_positions = false;
  double x_largest2 = 0.0;                  // max |x - q|^2
  bool x_cover_known = false;               // whether x_covered holds for this step's x
  bool x_covered = false;                   // x within the particles' reaches (by particle reach)
  bool x_listed = false;                    // known: the neighbour list stays valid at x
  std::vector<std::size_t> chunk_unlisted;  // displaced()'s per chunk
  std::vector<double> chunk_largest2;       // displaced()'s per chunk
  std::vector<std::size_t> chunk_outgrown;  // displaced()'s and start_step()'s, per chunk
  std::int64_t x_builds = 0;          // neighbour list builds when x was made (a rebuild wraps)
  double x_smallest_gap = 0.0;        // smallest candidate gap at x (feasibility guard's pass)
  bool x_smallest_gap_known = false;  // for the x of the last position update
  // The momentum update's velocities made in the last end positions' pass (no row held, no
  // force): update_momenta makes none where it would make the same.
  bool velocities_made = false;
  std::vector<Constraint> held, landed, violated;
  std::vector<bool> equality;
  double position_virial = 0.0;

  // Momentum update.
  std::vector<Constraint> momentum_rows;
};

}  // namespace deli
