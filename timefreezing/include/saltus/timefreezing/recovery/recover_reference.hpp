// The samples of a recovered time-freezing trajectory (recover_trajectory.hpp) at the discrete
// solution's element boundaries, as an ImportedReference for the event-driven re-simulation
// (hybrid/reference/resimulation.hpp: polish). Declared here; defined in recover_reference.hxx
// (compiled per scene by SALTUS_INSTANTIATE_TIME_FREEZING_SCENE, instantiate.hxx).
#pragma once

#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/timefreezing/recovery/discrete_events.hpp>

#include <vector>

namespace saltus::timefreezing {

/// The ImportedReference of a discrete time-freezing solution: the physical-time trajectory that
/// recover_trajectory read from `points` (the one recovery: every state, event and x+ comes from
/// `trajectory`), sampled where the discrete solution has its own values, with the discrete
/// solution's control. Polish it (hybrid/reference/resimulation.hpp: polish) to re-simulate it
/// with the event-driven simulator.
///
/// - Sample times: the first point and the end of every flowing element, at their clocks
///   (physical time; interior Radau stages are left out: with a_12 < 0 their clocks need not
///   increase). Frozen elements (detail::element_frozen, elements collapsed to a point included)
///   add no sample: their clock stands.
/// - Events: one per impact event of `trajectory` (a run of frozen elements, or an impact
///   absorbed into a flowing element, recover_trajectory.hpp), at its time t_e, which is an
///   element boundary of the points: the sample there is x- (the event's x_minus), the samples
///   after it belong to the next segment (ImportedReference::segment written out), and x+ (the
///   event's x_plus) is a sample at x_plus_time(trajectory, e): the event's time, or later where
///   the discretisation's clock ran on past the impact's instant before the impact ended (stamping
///   that x+ with the event time would put the motion over the advance into the reference as a
///   jump: the point-mass OCP of scenes/time_freezing_examples.hpp, 0.087 m and a re-simulation
///   0.09 away). When x_plus_time is not before the next sample's time, that sample is x+. Mode
///   changes without impact (release, stop, slip onset) are no events of the reference: the
///   state is continuous there and the re-simulation finds them itself.
/// - Every other sample: the trajectory's state at its time, on the trajectory's segment between
///   the same impacts.
/// - Inputs: the applied input of the sample's element; at every control-interval boundary the
///   sample is repeated with the next interval's input (same time, same segment), so that the
///   right-continuous interpolation of ImportedReference::input reproduces the piecewise-constant
///   control exactly.
/// Preconditions: `trajectory` is recover_trajectory's reading of the same points and n_s.
/// Throws InvalidArgument as recover_trajectory does (n_s outside 1..3, a point whose recorded
/// stage does not match n_s), and when an impact event of `trajectory` lies at no element boundary
/// of the points (a trajectory of other points).
template <Scene S, int ny, int nsw, int nu>
ImportedReference<S> recover_reference(const HybridTrajectory<S>& trajectory,
                                       const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       double frozen_tolerance = 1e-7);

namespace detail {

/// Throws InvalidArgument (naming `who`) unless `points` are the initial point and n_s points per
/// element, n_s in 1..3, each point recording its stage (FesdPoint::stage) for that n_s.
template <int ny, int nsw, int nu>
void check_stage_points(const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages, const char* who);

/// The discrete solution's control as samples for ImportedReference::input (t and u only; x is
/// left empty): the clock time and the applied input at the first point and at every element's
/// end, repeated with the next interval's input at every control-interval boundary. Its
/// right-continuous interpolation is the piecewise-constant control in physical time, also across
/// frozen elements (their samples share a time). recover_trajectory's input law.
template <Scene S, int ny, int nsw, int nu>
ImportedReference<S> control_samples(const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages);

}  // namespace detail

}  // namespace saltus::timefreezing
