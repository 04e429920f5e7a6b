// A tracking design for a hopper reference that starts in a stance, and the analysis options that
// check it (saltus/sensitivity/analysis/reference_analysis.hpp): used on the refined reference of
// the hopper over three holes (examples/hopper.cpp --json, bench/experiments/hopper_refinement).
#pragma once

#include "scenes/hopper.hpp"

#include <saltus/sensitivity/analysis/reference_analysis.hpp>

#include <iosfwd>

namespace saltus::scenes {

/// The analysis of a hopper reference under an LQR reference-spreading design: Q = 10 on q and 1
/// on v (also at T), R = `input_weight` I [1 / (N m)^2 relative to Q]; the stability check and
/// `runs` Monte Carlo runs (one thread) from deviations of the initial state that keep the first
/// stance: the foot on the ground and at rest, i.e. the 5-dimensional null space of the rows of
/// the gap, the normal velocity and the tangential velocity at the reference's start (its SVD),
/// the Monte Carlo deviations projected on it, and each perturbed start then projected onto the
/// stance itself (MonteCarloOptions::keep_initial_contacts: the null space keeps the foot on the
/// ground to first order, and the gap's curvature would leave it about 1e-7 m above, in flight;
/// measured on the refined reference's batch of 200: 28 runs kept the events without, 51 with).
/// One progress line per stage to `progress` (not
/// owned; null: none). Preconditions, not checked: the reference starts at rest with the foot
/// closed (the velocity rows use the contact Jacobians alone, exact at rest; the analysis' runs fail
/// with a named unplanned event otherwise). Throws InvalidArgument for runs < 0, an input weight
/// that is not finite and > 0, or a reference without segments.
ReferenceAnalysisOptions<Hopper> stance_start_lqr_analysis(const Hopper& hopper, const HybridTrajectory<Hopper>& reference,
                                                           int runs, double input_weight, std::ostream* progress);

/// The plant's simulation in the hopper's Monte Carlo runs: SimulationOptions{} with at most 2000
/// events and 200000 integration steps per segment (instead of 100000 and 10^7): a perturbed run
/// that chatters or whose closed loop is stiff for the explicit integrator fails there, with its
/// reason, instead of filling the memory with dense output (measured on the refined hopper: a run
/// held 3 GB after a few minutes).
SimulationOptions hopper_monte_carlo_simulation();

}  // namespace saltus::scenes
