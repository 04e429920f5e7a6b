// The discovery stage: the time-freezing homotopy run step by step, stopped where its contact
// schedule settles, i.e. where the schedule extracted from consecutive relaxed solutions stops
// changing (schedule_extraction.hpp). The contact-implicit homotopy is good at finding WHERE and
// WHEN contacts happen long before it is good at complementarity: on the guiding example the
// schedule is right from the first step (sigma = 1), on the plank-box flat landing the first two
// steps (sigma = 1e-2, 1e-3) agree on "land flat, slide, lift off" and the refined reference of that
// schedule is the better one (objective 40.77 against 55.33 for the schedule of the converged
// homotopy, whose stick phase the refinement does not solve: docs/refinement.md). The relaxed
// solutions need not be accurate: the refinement (refinement.hpp) makes the reference exact.
#pragma once

#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace saltus::timefreezing {

struct DiscoveryOptions {
  /// Homotopy steps at most (>= 1); each is one relaxed solve at sigma_k = sigma_0 kappa^k of the
  /// solver's options (MpccSolverOptions::Homotopy::sigma_0, kappa), warm-started from the one before.
  int max_steps = 6;
  /// Stop when this many consecutive steps give the same schedule (phases and guards; the event
  /// times may move), >= 1; 1 stops after the first step that gives a schedule.
  int agreeing_steps = 2;
  ScheduleExtractionOptions extraction;
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
  /// the last step's relaxed solution, its reference and its trajectory
  TimeFreezingOcpResult<S> relaxed;
  /// the schedule of the last step and its guess for refine_schedule (valid when `settled` or
  /// when the last step gave a schedule; `schedule_found` says which)
  ExtractedSchedule<S> discovered;
  bool schedule_found = false;
  /// the last agreeing_steps steps gave the same schedule
  bool settled = false;
  std::vector<DiscoveryStep> steps;
  std::string message;  ///< where and why the discovery stopped
  double seconds = 0.0;
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

}  // namespace saltus::timefreezing
