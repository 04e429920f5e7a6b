// The mode-schedule refinement of the hopper over three holes (refine_schedule, discover_schedule
// and discover_schedule_by_continuation for scenes::HopperOverThreeHoles), declared here and
// compiled once in hopper_holes_refinement.cpp, in its own library saltus_hopper_refinement: only
// the programs that refine the hopper (examples/hopper.cpp --json, bench/experiments, the
// release-stage test tests/test_flagship_refinement.cpp and the Python module _saltus) link it, so the tests' scene library does
// not compile it. The one-hole bed (HopperOverOneHole) runs on it too, as the three-hole type with
// its target (HopperOverThreeHoles::target, HopperOverOneHole::on_three_hole_rows) and horizon.
// With it, the settings of the hopper's chain (docs/refinement.md, "Hopper over three holes"):
// discovery from the paper's initialisation, the footsteps it finds, and the refinement of their
// schedule; and the whole chain in one call (run_hopper_chain, with the analysis of the refined
// reference), which examples/hopper.cpp --json, the one-hole test and the Python module run.
#pragma once

#include "scenes/hopper_footsteps.hpp"
#include "scenes/hopper_holes.hpp"

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>

#include <nlohmann/json.hpp>

#include <iosfwd>
#include <optional>
#include <string>

SALTUS_DECLARE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::Hopper)
SALTUS_DECLARE_SCHEDULE_REFINEMENT(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)

namespace saltus::scenes {

/// Discovery on the hopper over three holes: at most `steps` homotopy steps (sigma = 1, 0.1, ...)
/// after the hole continuation, each relaxed solution read by the gap alone (widened to
/// 0.15 sigma m, at most 1.5 cm; the normal velocity to 100 sigma m/s, at most 10 m/s: the relaxed
/// foot carries the body from up to a centimetre above the ground, at any speed), the extraction's
/// micro_flight_gap the same 1.5 cm. One progress line per stage and step to `progress` (not owned).
timefreezing::DiscoveryOptions hopper_discovery_options(int steps, std::ostream* progress);

/// The refinement's settings on the hopper: Radau IIA n_s = 4 on elements of at most 0.05 s (n_s
/// = 3 reaches lower optima, 87.4 .. 89.5, on 840 .. 1070 elements, but its per-phase
/// re-simulation check fails at every local error measured, 2e-7, 8e-8 and 5e-8, and it takes 1.4
/// to 3.3 times as long; docs/refinement.md, "Stage count and mesh path"),
/// Ipopt 3000 iterations, the sticking stances 5 % inside the friction cone, every phase at least
/// 20 ms long (without it the refinement shrinks three of the discovered stances to touches of
/// zero length, and its second mesh round does not solve), no schedule edit (an edit the last
/// solve's multipliers propose is reported, not solved: schedule_check_passed is then false),
/// Baumgarte's stabilisation of the closed foot at 20 / s (contact_stabilisation: without it the
/// stances' drift, up to 5e-5, reached the re-simulation at every lift-off), flights 5 mm clear of
/// the ground at their peak (flight_clearance, after the release's s^3 hump: without it two flights
/// skim the ground and the re-simulation touches down in them), the stances that end in a release
/// loaded to 20 N at their middle (stance_load: without it the stance before the last flight
/// grazes, lambda_n 0.13 N, and the re-simulation slips and lifts off early), every touchdown
/// coming in at 0.3 m/s or faster along the normal (touchdown_speed: measured with n_s = 3, the
/// optimum 89.51 against 91.68 and the refinement 138 s against 180 s), the mesh refined to local error
/// 2e-8 (split 4, 10 rounds of at most 1000 iterations each, each round started from the previous
/// solution, a round that splits at most a tenth of its grid also from its multipliers;
/// 2e-8, not the 2e-7 that the re-simulation check alone needs: the touchdowns' saltation norms
/// reach 5e4, and at 2e-7 (per-phase re-simulation 3.3e-7) the tracking design's nominal run, 1.7e-5
/// off the reference just before the touchdown at 1.864 s, is 0.6 off after it, where the analysis's
/// first order does not hold; at 2e-8 the nominal run stays within 1.3e-5),
/// the per-phase re-simulation in windows of 0.02 s (the stances are open-loop unstable at about
/// 40 / s). docs/refinement.md, "Hopper over three holes".
timefreezing::RefinementOptions hopper_refinement_options(std::ostream* progress);

/// The OCP's horizon for refine_schedule: from (q0, v0) at t = 0 to T [s] (default the three-hole
/// task's 2.5 s; the one-hole bed's is 1 s), |u_i| <= 60 N m. Throws InvalidArgument unless T is
/// finite and > 0.
timefreezing::OcpHorizon<Hopper> hopper_refinement_horizon(double T = HopperOverThreeHoles::horizon);

/// The guess the refinement starts from after discovery: the footsteps of the discovered schedule
/// (footsteps_of) with the kinematically consistent motion in them (footstep_guess), from q0 at
/// t = 0 to the pose `q_end` = (hip x [m], hip z [m], phi_hip [rad], phi_knee [rad]) at T [s] (default
/// the three-hole task's target and 2.5 s; the one-hole bed's are (1, 0.4, 0, 0) and 1 s). T must be
/// the horizon `discovery` was solved on (the footsteps' times are read from it; not checked).
/// `footsteps`, when not null, receives the footsteps read from the discovery. A discovery that
/// did not settle is accepted (the chain reads its last relaxed solution). Throws InvalidArgument
/// when discovery found no schedule, and as footsteps_of and footstep_guess.
timefreezing::ScheduleGuess<Hopper> hopper_guess_from(const timefreezing::DiscoveryResult<Hopper>& discovery,
                                                      HopperFootsteps* footsteps = nullptr,
                                                      const Vec<4>& q_end = HopperOverThreeHoles::q_target(),
                                                      double T = HopperOverThreeHoles::horizon);

/// The tasks of the hopper's chain: the flagship over three holes (HopperOverThreeHoles, T = 2.5 s)
/// and the one-hole bed (HopperOverOneHole, T = 1 s, run on the three-hole OCP type with its target).
enum class HopperTask { ThreeHoles, OneHole };

/// Where discovery starts: the paper's initialisation (the start state at every node, zero torques,
/// after the hole continuation) or the kinematic guess of three hops (HopperOverThreeHoles::hop_guess,
/// three holes only).
enum class HopperInitialisation { Paper, HopGuess };

/// The settings of the hopper's whole chain (run_hopper_chain): discovery, refinement, analysis.
struct HopperChainOptions {
  HopperTask task = HopperTask::ThreeHoles;
  HopperInitialisation initialisation = HopperInitialisation::Paper;
  /// The refinement's mesh tolerance (RefinementOptions::mesh.local_error_tolerance): 2e-8 over three
  /// holes (hopper_refinement_options), 2e-7 on the one-hole bed (its per-phase re-simulation check
  /// passes at 2.8e-7 measured, and the refinement takes 32-35 s instead of 64 s at 2e-8, both
  /// beside another build; tests/test_flagship_refinement.cpp).
  double local_error_tolerance = 2e-8;
  /// Closed-loop Monte Carlo runs of the analysis (>= 1), at perturbation size `perturbation_size`
  /// (the touchdowns' saltation norms reach 5e4: at 1e-5 a third of the runs leave the friction
  /// cone at a touchdown; docs/refinement.md, "The hopper's analysis").
  int runs = 200;
  double perturbation_size = 1e-6;
  /// Times, evenly spaced over the reference and its end among them, at which every run records its
  /// deviation and its first-order prediction (MonteCarloOptions::deviation_times; 0: none).
  int deviation_times = 60;
  /// Progress lines of every stage (not owned; null: silent).
  std::ostream* progress = nullptr;
};

/// The chain's settings for `task`: the three-hole flagship's as examples/hopper.cpp --json runs it
/// (200 runs, 60 deviation times), the one-hole bed's as its test runs it (local error 2e-7, 30
/// runs, no deviation times).
HopperChainOptions hopper_chain_options(HopperTask task);

/// What run_hopper_chain found, stage by stage.
struct HopperChain {
  HopperChainOptions options;
  timefreezing::DiscoveryResult<Hopper> discovery;
  HopperFootsteps footsteps;  ///< read off the discovered schedule (empty when discovery found none)
  /// The refinement of the footsteps' schedule; none when building its guess or the refinement threw
  /// (refinement_failure says why).
  std::optional<timefreezing::RefinementResult<Hopper>> refined;
  std::string refinement_failure;
  /// The refined reference's analysis (stance_start_lqr_analysis with R = I), when it converged.
  std::optional<ReferenceAnalysis<Hopper>> analysis;
};

/// The hopper's whole chain (docs/refinement.md, "Hopper over three holes"): discovery with
/// hopper_discovery_options(2) (by the hole continuation, or from hop_guess), the footsteps of its
/// schedule and their guess (hopper_guess_from), their refinement (hopper_refinement_options with the
/// options' mesh tolerance), and, when the refinement converged (its checks passed or not),
/// analyse_reference under hopper_monte_carlo_simulation()
/// with stance_start_lqr_analysis (R = I) at the options' runs, size and deviation times. A
/// saltus::Error of the guess or the refinement is kept (refinement_failure), not thrown. Used by
/// examples/hopper.cpp --json, tests/test_flagship_refinement.cpp and the Python bindings
/// (saltus.optimal_control.hopper_over_three_holes, hopper_over_one_hole). Throws InvalidArgument
/// for hop_guess on the one-hole bed, runs < 1, a perturbation size or a mesh tolerance that is not
/// finite or not > 0, deviation_times < 0; a saltus::Error thrown by discovery propagates.
HopperChain run_hopper_chain(const HopperChainOptions& options);

/// The chain's report, as examples/hopper.cpp --json prints it: {converged, initialisation ("paper"
/// or "hop_guess"), stage ("refined", "converged, checks failed: ...", "not converged", "discovery
/// (<why>)" or "refinement (<why>)"), relaxed_objective, discovery_seconds, discovery, footholds; when
/// the refinement ran (any stage but "discovery (...)" and "refinement (...)"):
/// mode_validity_violation, objective, schedule, schedule_edits, phase_resim_max_error,
/// refinement_seconds, events (the event times, s), max_path_violation, target_error,
/// solve_seconds, refinement (refinement_io.hpp); analysis (reference_analysis_io.hpp, with its
/// batch's runs and kept_event_sequence also at its top level)}.
nlohmann::ordered_json to_json(const HopperChain& chain);

}  // namespace saltus::scenes
