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
  std::vector<FrozenPhase<nx>> frozen_phases;
  std::vector<SwitchPoint> switch_points;
  /// In physical time, recovered directly (recover_trajectory); also when not converged(), then
  /// only a reading of the unconverged points, not a motion of the scene.
  HybridTrajectory<S> trajectory;
  MpccSolution solution;  ///< the homotopy's result: converged, complementarity, steps, times
  bool converged() const { return solution.converged; }
  /// The state (q, v, t, L, g) at the end of the horizon.
  const auto& final_state() const { return points.back().y; }
};


/// How simulate_time_freezing splits the horizon into MPCCs.
enum class SimulationSplit {
  PerControlInterval,  ///< one MPCC per control interval, each from the previous one's end (NOSNOC's integrator)
  WholeHorizon,        ///< one MPCC over all control intervals
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
/// did; solution holds the totals (iterations, seconds; complementarity the largest; steps all).
/// Throws InvalidArgument for bad options or initial states, as FesdMpcc and solve_mpcc do.
template <Scene S, class InputLaw = NoObjective>
TimeFreezingSimulation<S> simulate_time_freezing(const TimeFreezingSystem<S>& system, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, FesdOptions fesd, const InputLaw& law = {},
                                                 const MpccSolverOptions& solver = {},
                                                 SimulationSplit split = SimulationSplit::PerControlInterval);

}  // namespace saltus::timefreezing
