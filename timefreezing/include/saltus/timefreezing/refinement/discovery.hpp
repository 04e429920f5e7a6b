// The discovery stage: the time-freezing homotopy run step by step, stopped where its contact
// schedule settles, i.e. where the schedule extracted from consecutive relaxed solutions stops
// changing (schedule_extraction.hpp). The contact-implicit homotopy is good at finding WHERE and
// WHEN contacts happen long before it is good at complementarity: on the guiding example the
// schedule is right from the first step (sigma = 1), on the plank-box flat landing the first two
// steps (sigma = 1e-2, 1e-3) agree on "land flat, slide, lift off" and the refined reference of that
// schedule is the better one (objective 40.88 against 55.33 for the schedule of the converged
// homotopy, whose stick phase the refinement does not solve: docs/refinement.md). The relaxed
// solutions need not be accurate: the refinement (refinement.hpp) makes the reference exact.
#pragma once

#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace saltus::timefreezing {

/// How discovery reads the contacts of a relaxed solution: recover_trajectory with its gap and
/// normal-velocity tolerances widened to the relaxation of the step, sigma_k:
///   gap_tolerance      = min(gap_max,      max(recovery.gap_tolerance,      gap_per_sigma      * sigma_k))  [m],
///   velocity_tolerance = min(velocity_max, max(recovery.velocity_tolerance, velocity_per_sigma * sigma_k))  [m/s].
/// The default (both factors 0) is the exact reading. A relaxed stance keeps its contact only
/// within the relaxation (G H <= sigma lets the gap and the normal velocity sit away from zero
/// while the contact force acts), and whether the widened reading helps depends on the OCP
/// (docs/refinement.md, "Discovery"; measured, one thread):
/// - plank-box short landing (scenes::PlankBoxShortLanding): at sigma = 1e-2 the landed box rests
///   1e-4 m above the plank creeping upward at 4e-3 .. 6e-3 m/s; the exact reading sees no contact
///   and discovery settles on a hover (refined objective 97.3 against the relaxed 58.6); with
///   factors 0.1 and 1 the first step gives "land flat, slide, lift off" (refined 38.6 at h = 0.02).
/// - plank-box flat landing (the flagship): the exact reading settles on "land flat, slide, lift
///   off" at sigma = 1e-2, 1e-3; with factors 0.1 and 1 the step at sigma = 1e-3 extends the
///   contact into the box's near-rest before the lift-off and reads a stick phase there, which
///   the steps after agree on and whose refinement fails.
/// The tangential velocity tolerance is never widened (with it widened too the flagship's first
/// step already read the stick phase). Factors >= 0, caps > 0.
struct RelaxedContactReading {
  double gap_per_sigma = 0.0;       ///< [m per unit of sigma]
  double velocity_per_sigma = 0.0;  ///< [m/s per unit of sigma]
  double gap_max = 1e-3;            ///< [m], the extraction's micro_flight_gap
  double velocity_max = 1e-2;       ///< [m/s]
  TrajectoryRecoveryOptions recovery;  ///< the tolerances' floor and the other reading options

  /// recover_trajectory's options at relaxation sigma (>= 0).
  TrajectoryRecoveryOptions at(double sigma) const;
};

struct DiscoveryOptions {
  /// Homotopy steps at most (>= 1); each is one relaxed solve at sigma_k = sigma_0 kappa^k of the
  /// solver's options (MpccSolverOptions::Homotopy::sigma_0, kappa), warm-started from the one before.
  int max_steps = 6;
  /// Stop when this many consecutive steps give the same schedule (phases and guards; the event
  /// times may move), >= 1; 1 stops after the first step that gives a schedule.
  int agreeing_steps = 2;
  ScheduleExtractionOptions extraction;
  RelaxedContactReading reading;
  std::ostream* progress = nullptr;  ///< one line per homotopy step when not null; not owned

  /// Throws InvalidArgument naming the first field out of its domain.
  void validate() const;
};

/// One homotopy step of the discovery.
struct DiscoveryStep {
  int index = 0;
  double sigma = 0.0;
  double complementarity = 0.0;
  double objective = 0.0;
  std::string ipopt_status;
  int ipopt_iterations = 0;
  double seconds = 0.0;
  /// describe() of the step's schedule, or "" when none could be extracted (extraction_error says why)
  std::string schedule;
  std::string extraction_error;
};

template <Scene S>
struct DiscoveryResult {
  /// the last solved step's relaxed solution, its reference and its trajectory (read with the
  /// exact tolerances of recover_trajectory); empty when no step was solved (a continuation
  /// stage or the first step failed)
  TimeFreezingOcpResult<S> relaxed;
  /// the last solved step's relaxed solution read with DiscoveryOptions::reading (sigma-scaled
  /// tolerances): the trajectory `discovered` is extracted from
  HybridTrajectory<S> relaxed_reading;
  /// the schedule of the last solved step and its guess for refine_schedule; valid only when
  /// `schedule_found` (when that step's extraction failed it may still hold an earlier step's)
  ExtractedSchedule<S> discovered;
  /// whether `discovered` is the last solved step's schedule (`settled` says whether it settled)
  bool schedule_found = false;
  /// the last agreeing_steps steps gave the same schedule
  bool settled = false;
  std::vector<DiscoveryStep> steps;
  std::string message;  ///< where and why the discovery stopped
  /// discover_schedule_by_continuation: the continuation's relaxed solves, one per stage, and their
  /// wall time [s] (included in `seconds`); empty and 0 for discover_schedule
  std::vector<MpccHomotopyStep> continuation_steps;
  double continuation_seconds = 0.0;
  double seconds = 0.0;  ///< wall time of the whole discovery [s]
};

/// Runs the homotopy of the time-freezing OCP `ocp` from (q0, v0) on the grid `fesd` with the
/// solver's relaxation (solver.homotopy.sigma_0, solver.homotopy.kappa; one Ipopt solve per step, no polish), extracts
/// the schedule of every step's relaxed solution (the scene's contacts: `scene` must be the
/// system's scene) and stops when options.agreeing_steps consecutive steps agree, or after
/// options.max_steps, or at a step Ipopt does not solve (the result keeps the last solved step).
/// Throws InvalidArgument for bad options or states (solve_time_freezing_ocp's conditions).
template <Scene S, class Ocp>
DiscoveryResult<S> discover_schedule(const S& scene, const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                     const Vec<S::nq>& q0, const Vec<S::nq>& v0, const FesdOptions& fesd,
                                     const MpccSolverOptions& solver, const DiscoveryOptions& options = {});

/// discover_schedule from a guess of the motion instead of the initial state at every stage point
/// (the second initialisation, as solve_time_freezing_ocp_from_guess: `guess(t)` -> (q, v) at
/// physical time t, FesdMpcc::initial_point_from_guess). E.g. the hopper's hop_guess
/// (scenes/hopper_holes.hpp): where the feet go, not how. Throws InvalidArgument as
/// discover_schedule and for a guess that is not finite.
template <Scene S, class Ocp>
DiscoveryResult<S> discover_schedule_from_guess(const S& scene, const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                                const Vec<S::nq>& q0, const Vec<S::nq>& v0, const FesdOptions& fesd,
                                                const MotionGuess& guess, const MpccSolverOptions& solver,
                                                const DiscoveryOptions& options = {});

/// discover_schedule preceded by a continuation on the OCP's data (as
/// solve_time_freezing_ocp_by_continuation): one relaxed solve per OCP of `continuation` at the
/// solver's sigma_0, in order, the first from the initial state at every stage point, each
/// warm-started from the one before; then the discovery's homotopy steps on `ocp` from the last
/// stage's solution. The hopper over three holes grows its holes this way
/// (scenes/hopper_holes.hpp, hole_continuation): nothing in it hints at the contacts. A stage that
/// Ipopt does not solve ends the discovery without a step (`message` says which). One progress line
/// per stage and per step. Throws InvalidArgument as discover_schedule and for an empty continuation.
template <Scene S, class Ocp>
DiscoveryResult<S> discover_schedule_by_continuation(const S& scene, const TimeFreezingSystem<S>& system,
                                                     const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                     const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                     const FesdOptions& fesd, const MpccSolverOptions& solver,
                                                     const DiscoveryOptions& options = {});

}  // namespace saltus::timefreezing
