// Simulation of the time-freezing system with FESD under a given input law: the FESD MPCC with
// its decisions fixed (no controls, no clock constraint, s = 1), solved by the MPCC homotopy, and
// read by the recovery (recovery/). Declared here, defined in simulate.hxx: a program that includes
// this header links the driver from the translation unit that instantiates it
// (saltus/timefreezing/instantiate.hpp), or includes <saltus/timefreezing/header_only.hpp>.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>
#include <saltus/timefreezing/recovery/recover_trajectory.hpp>

#include <vector>

namespace saltus::timefreezing {

template <Scene S>
struct TimeFreezingSimulation {
  static constexpr int nx = 2 * S::nq;
  using Point = typename FesdMpcc<S>::Point;
  std::vector<Point> points;  ///< the initial point and every stage point, in numerical time
  std::vector<double> element_lengths;        ///< h of every element, in order
  /// The runs of frozen elements (impacts), in order; FrozenPhase::cut marks a run that ended before
  /// its impact did (its x_plus is then not the impact's outcome; the trajectory's event's is).
  std::vector<FrozenPhase<nx>> frozen_phases;
  std::vector<SwitchPoint> switch_points;
  /// In physical time, recovered directly (recover_trajectory); also when not converged(), then
  /// only a reading of the unconverged points, not a motion of the scene.
  HybridTrajectory<S> trajectory;
  MpccSolution solution;  ///< the homotopy's result: converged, complementarity, steps, times
  int fallbacks = 0;       ///< control intervals solved by the fallback (SimulationFallback)
  /// One line per control interval that failed its first attempt (the fallback enabled): which
  /// attempt solved it, or that none did (e.g. "interval 3 (not converged): solved on 8 finite
  /// elements, contact-side selection off (as given)"; "turned on" or "turned off" where the
  /// fallback toggled it). Intervals are counted from 0 here and in the
  /// message, from 1 in the progress lines.
  std::vector<std::string> fallback_log;
  /// The finite elements of every control interval as solved (fesd.grid.finite_elements unless the
  /// fallback refined it); one entry for SimulationSplit::WholeHorizon.
  std::vector<int> finite_elements;
  bool converged() const { return solution.converged; }
  /// The state (q, v, t, L, g) at the end of the horizon.
  const auto& final_state() const { return points.back().y; }
};


/// How simulate_time_freezing splits the horizon into MPCCs.
enum class SimulationSplit {
  PerControlInterval,  ///< one MPCC per control interval, each from the previous one's end (NOSNOC's integrator)
  WholeHorizon,        ///< one MPCC over all control intervals
};

/// What simulate_time_freezing does when a control interval fails (PerControlInterval, also with
/// one control interval; WholeHorizon solves its MPCC once and checks nothing): its homotopy did
/// not converge, or it converged with a flaw: an integrated gap descending by more than
/// penetration_tolerance (the gap's drift), or the physical clock running back between two points
/// by more than clock_reversal_tolerance (two modes mixed in one collocation element). The
/// interval is solved again from the same start state, in this order, and the first attempt that
/// succeeds is kept:
///  1. on finer grids, finite_elements times 2, 4, ... (max_refinements doublings); skipped for an
///     interval that converged with a flaw without the contact-side selection
///     (FesdOptions::regularisation.contact_side), where finer grids without it converged to wrong
///     motions (the guiding example, scenes::Example3: its interval at tau = 0.5, q1 6.9e-4 off);
///  2. with the contact-side selection toggled (off where it was on; contact_side_weight where it
///     was off), on the interval's grid and the same finer grids; skipped for an interval that
///     converged with a flaw with the selection on. A selection turned on that solved an interval
///     stays on for the rest of the run (as solve_mpcc keeps a slower homotopy once a step needed
///     it: the drift it cured would come back in every later interval in contact); one turned off
///     rescues its interval only (without the selection a rod resting on both ends can mix its
///     impact's end and its rest in one element).
/// A finer grid applies to the failed interval only. When no attempt succeeds the run goes on from
/// the least bad one (the converged attempt whose flaws exceed their tolerances the least, else the
/// first attempt), and converged() is false. With the fallback disabled nothing is checked: a
/// converged interval counts as converged whatever its flaws.
/// Why (bench/time_freezing_battery, docs/time_freezing.md, "Robustness on easy problems"):
///  1. FESD places every switch on an element boundary and a control interval holds one active set
///     per element, so an interval in which the motion passes through more modes than it has
///     elements (a touchdown, the impact's frozen phase and the rest after it, inside one interval
///     of two elements) has no complementary solution: the homotopy stalls at sigma ~ 1e-2 with
///     Ipopt's Infeasible_Problem_Detected (a point mass dropped from 0.8 m with a_n = 100 on
///     NOSNOC's bouncing-ball grid). More elements give the switches room.
///  2. Where the gap is exactly zero (a frozen phase, a rest, a slide) its step function is free,
///     and without the contact-side selection a converged homotopy can let the gap drift to
///     -1e-5 (NOSNOC's frictional landing), or mix an impact's end and a rest in one element (the
///     rod landing flat from 0.3 m: its clock 1.4e-3 s back, its stop 1.7e-5 off).
struct SimulationFallback {
  bool enabled = true;  ///< false: a failed interval is kept as it is and the run goes on
  /// Doublings of the interval's finite elements, 0..6 (3: up to 8 times the elements; Painleve's
  /// rod with a_n = 10 converges on 16 elements of its interval and not on 8 or fewer).
  int max_refinements = 3;
  /// m (the unit of the scene's gaps), >= 0 (0: any descent, round-off included, fails; infinity
  /// turns the check off). Per interval: a converged interval whose integrated gaps
  /// (TimeFreezingSystem) descend more than this below zero, or below their start where that is
  /// below zero, has drifted and is solved again. The integrated gap, not gap(q): it stays put
  /// wherever the collocation holds J_n v = 0 (a frozen phase, a rest), so it shows the drift of
  /// the complementarity (about 1e-5 in NOSNOC's frictional landing and in the guiding example)
  /// and not the collocation's own error of a gap nonlinear in q while a body turns on its contact
  /// (Painleve's rod sticking after its impact without collision: gap(q) 1.0e-7 below zero on 8
  /// elements, its integrated gap 4.7e-13).
  double penetration_tolerance = 1e-8;
  /// s: the exact clock never runs back (t' = Theta >= 0); a step back larger than this means the
  /// collocation mixed two modes in one element.
  static constexpr double clock_reversal_tolerance = 1e-8;
  /// The contact-side weight of attempt 2 where the user's was 0 (> 0; 1e-2: docs/time_freezing.md).
  double contact_side_weight = 1e-2;
};

/// Settings of simulate_time_freezing beyond the FESD grid and the MPCC solver.
struct TimeFreezingSimulationOptions {
  SimulationSplit split = SimulationSplit::PerControlInterval;
  SimulationFallback fallback;
};

/// Simulates the time-freezing system of `system` from (q0, v0) at physical time
/// fesd.clock.initial_time over the numerical horizon fesd.grid.horizon under the input law of `law` (an
/// object with `template <class T> VecT<T, nu> input(const T& t, const VecT<T, nu>& decision) const`,
/// t the physical time; NoObjective applies u = 0).
/// fesd.clock (constraint, speed_of_time_max), the speed-of-time weight and the control bounds are overridden (no clock constraint,
/// s = 1, decisions fixed at 0). The input law must be smooth inside each control interval (a kink
/// in time belongs on a control-interval boundary, where the grid is fixed).
/// PerControlInterval (the default) solves N small MPCCs in sequence; the cross-complementarity
/// across their boundaries is then not imposed (the first element of each interval has no
/// previous end point), as in NOSNOC's integrator.
/// With solver.progress set, a line "simulate_time_freezing: control interval k of N" precedes each
/// interval's homotopy lines (PerControlInterval).
/// Returns the result whether or not every homotopy converged: converged() is true only when all
/// did; solution holds the totals (iterations and seconds, the fallback's failed attempts included;
/// complementarity the largest; steps those of the kept attempts).
/// Throws InvalidArgument for bad options or initial states, as FesdMpcc and solve_mpcc do.
template <Scene S, class InputLaw = NoObjective>
TimeFreezingSimulation<S> simulate_time_freezing(const TimeFreezingSystem<S>& system, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, FesdOptions fesd, const InputLaw& law = {},
                                                 const MpccSolverOptions& solver = {},
                                                 const TimeFreezingSimulationOptions& options = {});

}  // namespace saltus::timefreezing
