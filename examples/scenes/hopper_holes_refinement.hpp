// The mode-schedule refinement of the hopper over three holes (refine_schedule, discover_schedule
// and discover_schedule_by_continuation for scenes::HopperOverThreeHoles), declared here and
// compiled once in hopper_holes_refinement.cpp, in its own library saltus_hopper_refinement: only
// the programs that refine the hopper (examples/hopper.cpp --json, bench/experiments, the
// release-stage test tests/test_flagship_refinement.cpp) link it, so the tests' scene library does
// not compile it. The one-hole bed (HopperOverOneHole) runs on it too, as the three-hole type with
// its target (HopperOverThreeHoles::target, HopperOverOneHole::on_three_hole_rows) and horizon.
// With it, the settings of the hopper's chain (docs/refinement.md, "Hopper over three holes"):
// discovery from the paper's initialisation, the footsteps it finds, and the refinement of their
// schedule.
#pragma once

#include "scenes/hopper_footsteps.hpp"
#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>

#include <iosfwd>

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

}  // namespace saltus::scenes
