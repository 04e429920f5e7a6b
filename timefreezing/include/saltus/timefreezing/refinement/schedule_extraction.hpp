// The mode schedule of a hybrid trajectory: discovery's output. The trajectory may be the
// recovered reading of a relaxed time-freezing solution (recovery/recover_trajectory.hpp), a
// re-simulated reference imported from elsewhere, or any HybridTrajectory of the scene; its
// segments give the phases, its events the guards and the event times, its dense output and input
// law the guess of the motion (schedule_guess.hpp).
//
// Relaxed solutions float and micro-bounce, so the segments are cleaned before they become phases
// (the rules, in this order):
//   1. micro-flights: a contact that is open in a segment but closed in the segments on both
//      sides, whose gap stays below micro_flight_gap over the segment, is read as closed there
//      (with the mode of the segment before): a stance whose gap wanders within the relaxation;
//   2. micro-phases: a segment shorter than min_phase_duration is dropped; the boundary between
//      its neighbours sits at its middle;
//   3. neighbours with the same mode merge into one phase (their event vanishes);
//   4. each remaining boundary gets the guards the mode change needs (guards_between), plus the
//      touchdowns of an impact that the trajectory recorded there on contacts that stay closed.
// Thresholds: ScheduleExtractionOptions (defaults and why, there).
#pragma once

#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <saltus/timefreezing/refinement/schedule_guess.hpp>

#include <string>
#include <vector>

namespace saltus::timefreezing {

struct ScheduleExtractionOptions {
  /// Rule 2 [s], >= 0. A relaxed solution's spurious segments last a few finite elements or less
  /// (the plank-box and point-mass OCPs' converged homotopies: none; their elements are 0.017-0.05 s
  /// long), while the flagships' physical phases last >= 0.1 s: 5e-3 s separates the two.
  double min_phase_duration = 5e-3;
  /// Rule 1 [m], >= 0: below the smallest intended clearance of the flagships (the plank-box flies
  /// 5 cm above the plank, the hopper's foot lifts >= 1 cm) and above the relaxation's drift of a
  /// stance gap (1e-5 .. 1e-4 m at complementarity 1e-4 .. 1e-9).
  double micro_flight_gap = 1e-3;

  void validate() const {
    SALTUS_REQUIRE(std::isfinite(min_phase_duration) && min_phase_duration >= 0.0,
                   "schedule extraction: min_phase_duration must be >= 0, got ", min_phase_duration);
    SALTUS_REQUIRE(std::isfinite(micro_flight_gap) && micro_flight_gap >= 0.0,
                   "schedule extraction: micro_flight_gap must be >= 0, got ", micro_flight_gap);
  }
};

/// What the extraction did to the segments (for reports: which rule merged what).
struct ExtractionNote {
  std::string rule;  ///< "micro-flight", "micro-phase", "same mode"
  double t_begin = 0.0, t_end = 0.0;
};

template <Scene S>
struct ExtractedSchedule {
  ScheduleGuess<S> guess;            ///< the schedule, its event times, and the motion as its guess
  std::vector<ExtractionNote> notes;
};

/// The schedule of `trajectory` (file comment) with the trajectory as the guess of the motion (its
/// dense output per phase, its input law). The trajectory is copied into the guess's functions.
/// @throws InvalidArgument for a trajectory without segments, a segment without dense output, or
///   bad options; and as validated() when the cleaned schedule is still inconsistent (naming the
///   event).
template <Scene S>
ExtractedSchedule<S> extract_schedule(const S& scene, const HybridTrajectory<S>& trajectory,
                                      const ScheduleExtractionOptions& options = {});

}  // namespace saltus::timefreezing

#include <saltus/timefreezing/refinement/schedule_extraction.hxx>
