// The physical-time HybridTrajectory of a discrete time-freezing solution (time-freezing Theorem
// 5), recovered without re-simulation: frozen runs become impact events, modes are read off the
// states and step functions. Declared here; defined in recover_trajectory.hxx (compiled per scene by
// SALTUS_INSTANTIATE_TIME_FREEZING_SCENE, instantiate.hxx).
#pragma once

#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <saltus/timefreezing/recovery/recover_reference.hpp>

#include <cstddef>
#include <vector>

namespace saltus::timefreezing {


/// Tolerances of recover_trajectory.
struct TrajectoryRecoveryOptions {
  /// A contact is closed at a point where its gap is <= gap_tolerance [m] and its normal velocity
  /// |J_n v| <= velocity_tolerance [m/s] (a point that reaches the surface at a negative J_n v, the
  /// end of a flight, is not closed); a closed contact with friction slips where |J_t v| >
  /// tangential_velocity_tolerance [m/s] (with that sign) and sticks where not. All > 0. Sized above the
  /// discretisation's residual drift (a frozen phase's gap of -1.6e-5 without the contact-side
  /// selection, fesd.hpp) and below the motions' own scales.
  double gap_tolerance = 1e-4;
  double velocity_tolerance = 1e-4;
  double tangential_velocity_tolerance = 1e-4;
  /// Elements whose clock advances by at most frozen_tolerance * h are frozen, and so are those
  /// detail::element_frozen adds (a frozen first stage, a crept clock with a velocity jump).
  double frozen_tolerance = 1e-7;
  /// In a flowing element, a contact that the state calls closed (above) is read as open when its
  /// closing weight w = (1 - alpha_gap)(1 - alpha_vn) (alpha_gap, alpha_vn: the step functions of
  /// its gap and J_n v switching functions, FesdPoint::alpha[3 i], [3 i + 1]) at the element's
  /// last interior stage point (recover_trajectory: "Modes"; TimeFreezingSystem::closing_weight)
  /// is below closing_weight_tolerance (dimensionless, in (0, 1)): the auxiliary dynamics then
  /// carry no force, as after a tangential lift-off, where the state stays within the tolerances
  /// above (J_n v = g (t - 1.5)^2 in the guiding example, Example 3) while the weight falls
  /// through zero transversally (w = 1 - 1 / (2 (2 - t)) there). Sized above the weights that a converged
  /// homotopy leaves in the degenerate elements next to such a switch (measured: up to 3e-6 at a
  /// complementarity of 1e-14, Example 3 at n_s = 2 with 1,120 elements). Points outside flowing
  /// elements (the first point, and x+ of a frozen run at the end of the horizon) and the search
  /// for x+ of an absorbed impact are read by the state alone: their step functions say nothing
  /// about a force (the first point's are a placeholder, 0.5).
  double closing_weight_tolerance = 1e-4;
};

/// Recovers the physical-time HybridTrajectory of a discrete time-freezing solution (time-freezing
/// Theorem 5), without re-simulating it: the frozen intervals are removed and every run of frozen
/// elements becomes an impact event; the contact modes are read off the states; a mode change
/// between two flowing elements becomes an event without impact. Compare polish() (resimulation.hpp),
/// which re-simulates the samples of this trajectory (recover_reference) with the event-driven
/// simulator.
///
/// - Modes: per flowing element and contact, from the switching functions at the element's last
///   interior stage point (c_r < 1: Radau's end point is the next element's start and lies on the
///   switching surface when a switch is there; n_s = 1 has only the end point) and the contact's
///   closing weight there, with the tolerances of TrajectoryRecoveryOptions. A frictionless
///   contact (or mu = 0) that is closed is ContactState::slip(0), as the simulator stores it. A
///   switch inside an element (the grid did not locate it, e.g. a slip-stick with
///   switching.velocity_detection = false) appears at the element boundary next to it.
/// - Segments: one per run of flowing elements with the same mode. Dense output: per element the
///   polynomial through its start point and its n_s stage points, in physical time (degree n_s;
///   exact where the clock runs at a constant rate: Theta = 1). Where the stage clocks are not
///   strictly increasing (Radau's interior stages under a nearly frozen clock) the piece is the
///   straight line between the element's end points.
/// - Impact events (runs of frozen elements): at the clock time of the run's start, x- its start
///   state and x+ its end state, mode_before the previous segment's mode and mode_after the next
///   one's; one transition with impact = true and a Touchdown guard for every contact that was
///   open before and approaching (gap <= gap_tolerance, J_n v < -velocity_tolerance at x-): both
///   corners of a flat landing. The transition's impulse_mode names the contacts whose closing
///   weight (1 - alpha_gap)(1 - alpha_vn) reached 1/2 in the run, with the impact solver's roles
///   (stick: frictionless, or at tangential rest after the impact; slip: along the sign of J_t v
///   at x+), so that jump_gains() (sensitivity/jump_gain.hpp) can differentiate its jump map; the
///   impulse itself is not recovered (left zero). A run without an approaching open contact has no
///   guard (Transition::guards empty). When the run's clock advanced (FrozenPhase::clock_advance:
///   its last element went on past the end of the impact), x+ is the state that much later and
///   the next segment's first piece holds x+ constant over the advance: the trajectory is off by
///   the motion over clock_advance there. The same when the run ends before the impact does (a
///   contact with gap <= gap_tolerance still approaching, J_n v < -velocity_tolerance, at the
///   run's end: the last part of the impact was resolved by the next, flowing element, which
///   switching.velocity_detection = false allows; the plank-box flagship's landing): x+ is the first
///   stage point of that element from which on no such contact approaches, held over its clock
///   advance.
/// - Mode changes without impact: x- = x+ = the boundary state; guards per contact: Touchdown
///   (open -> closed without a frozen run: a touchdown at zero normal velocity), Release (closed ->
///   open), Stop (slip -> stick), SlipOnset (stick -> slip, or a reversal of the slip direction).
/// - Absorbed impacts: a touchdown at J_n v(x-) < -velocity_tolerance that is not a frozen run is
///   an impact the discretisation absorbed into a flowing element (the clock ran through it).
///   That is the rule, not the exception, under FesdOptions::switching.velocity_detection = false
///   (the flagship OCPs' setting): the end of an impact is a switch of J_n v, which the grid then
///   does not locate, so an impact shorter than its element ends inside it (the plank-box flat
///   landing: J_n v = -1.04 m/s against a_n = 50 lasts about 1.04 / 50 = 0.02 of numerical time at
///   speed of time 1, less at s > 1, in elements of h0 = 0.05). It is read as an impact event at
///   the element's start: x- there, x+ the state at the element's first stage point from which on
///   every struck contact is closed, held over the clock advance to it (as for a frozen run's
///   advance), guards Touchdown for the struck contacts (and the mode changes of the others),
///   impulse_mode for the struck contacts. x+ is then off by the motion over that advance, and a
///   jump gain of it is refused unless x+ is the impact law's post-impact state to 1e-9.
/// - The input law u(t) is the discrete solution's piecewise-constant control in physical time
///   (detail::control_samples: ImportedReference::input of the element ends' inputs,
///   right-continuous at control-interval boundaries), whatever x and the mode.
/// The trajectory is a reading of the points whether or not their homotopy converged: the one of
/// an unconverged solution (complementarity above tolerance) is not a motion of the scene (events
/// off, states below the surface) and its status still says Completed; check converged() first.
/// Throws InvalidArgument for n_s outside 1..3, for points whose recorded stage does not match
/// n_s, for tolerances that are not finite and > 0, and for a closing_weight_tolerance outside
/// (0, 1).
template <Scene S, int ny, int nsw, int nu>
HybridTrajectory<S> recover_trajectory(const TimeFreezingSystem<S>& system,
                                       const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       const TrajectoryRecoveryOptions& options = {});

/// The physical time [s] that event `e` of a trajectory from recover_trajectory reads its x+ at:
/// the event's time, or later where the discretisation's clock ran on past the impact's instant
/// before the impact ended (recover_trajectory's docstring: x+ is held constant over that
/// advance, as the first piece of the next segment). Throws InvalidArgument for e out of range.
template <Scene S>
double x_plus_time(const HybridTrajectory<S>& traj, std::size_t e) {
  SALTUS_REQUIRE(e < traj.events.size(), "x_plus_time: event ", e, " of ", traj.events.size());
  const double t = traj.events[e].t;
  for (const Segment<S>& seg : traj.segments)
    if (seg.t_begin == t && !seg.x.empty()) {
      const auto& first = seg.x.pieces().front();
      if (first.degree == 0 && first.t0 == t && first.t1 > t && first.c.col(0) == traj.events[e].x_plus) return first.t1;
    }
  return t;
}

}  // namespace saltus::timefreezing
