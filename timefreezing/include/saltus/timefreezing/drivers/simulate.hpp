// Simulation of the time-freezing system with FESD under a given input law: the FESD MPCC with
// its decisions fixed (no controls, no clock constraint, s = 1), solved by the MPCC homotopy, and
// read by the recovery (recovery/).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>
#include <saltus/timefreezing/recovery/recover_trajectory.hpp>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
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
/// fesd.initial_time over the numerical horizon fesd.horizon under the input law of `law` (an
/// object with `template <class T> VecT<T, nu> input(const T& t, const VecT<T, nu>& decision) const`,
/// t the physical time; NoObjective applies u = 0).
/// fesd.clock, speed_of_time_max and the control bounds are overridden (no clock constraint,
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
                                                 SimulationSplit split = SimulationSplit::PerControlInterval) {
  constexpr int nq = S::nq;
  // Checked here too: the split below divides by them before FesdMpcc would see them.
  SALTUS_REQUIRE(fesd.control_intervals >= 1, "FESD: control_intervals must be >= 1, got ", fesd.control_intervals);
  SALTUS_REQUIRE(std::isfinite(fesd.horizon) && fesd.horizon > 0.0, "FESD: the numerical horizon must be > 0, got ",
                 fesd.horizon);
  fesd.clock = ClockConstraint::None;
  fesd.speed_of_time_max = 1.0;
  fesd.speed_of_time_weight = 0.0;
  fesd.control_lower = Eigen::VectorXd::Zero(S::nu);
  fesd.control_upper = Eigen::VectorXd::Zero(S::nu);
  TimeFreezingSimulation<S> out;
  const int pieces = split == SimulationSplit::WholeHorizon ? 1 : fesd.control_intervals;
  FesdOptions piece = fesd;
  if (pieces > 1) {
    piece.control_intervals = 1;
    piece.horizon = fesd.horizon / fesd.control_intervals;
  }
  Vec<nq> q = q0, v = v0;
  double tau0 = 0.0, cost0 = 0.0;
  out.solution.converged = true;
  for (int k = 0; k < pieces; ++k) {
    // Which MPCC the progress lines that follow belong to (each restarts at step 0).
    if (solver.progress && pieces > 1)
      *solver.progress << "simulate_time_freezing: control interval " << k + 1 << " of " << pieces << "\n";
    const FesdMpcc<S, InputLaw> problem(system, law, q, v, piece);
    MpccSolution sol = solve_mpcc(problem, solver);
    auto pts = problem.points(sol.x);
    for (auto& p : pts) {
      p.tau += tau0;
      p.interval += k;
      p.y[TimeFreezingSystem<S>::cost_index] += cost0;
    }
    out.points.insert(out.points.end(), pts.begin() + (k == 0 ? 0 : 1), pts.end());
    const auto& end = out.points.back().y;
    q = end.template head<nq>();
    v = end.template segment<nq>(nq);
    piece.initial_time = end[TimeFreezingSystem<S>::clock_index];
    // The user's initial state was checked; a later interval starts where the previous one
    // ended, which may be below a contact by the discretisation's own drift (a frozen phase's gap
    // of -1e-5, see the note): not a user error.
    piece.gap_tolerance = std::numeric_limits<double>::infinity();
    cost0 = end[TimeFreezingSystem<S>::cost_index];
    tau0 += piece.horizon;
    // Totals.
    MpccSolution& t = out.solution;
    t.converged = t.converged && sol.converged;
    if (!sol.converged && t.message.empty()) t.message = "control interval " + std::to_string(k) + ": " + sol.message;
    if (sol.complementarity >= t.complementarity) {
      t.complementarity = sol.complementarity;
      t.worst_pair = "interval " + std::to_string(k) + ": " + sol.worst_pair;
    }
    t.constraint_violation = std::max(t.constraint_violation, sol.constraint_violation);
    t.ipopt_iterations += sol.ipopt_iterations;
    t.seconds += sol.seconds;
    t.objective += sol.objective;
    t.steps.insert(t.steps.end(), sol.steps.begin(), sol.steps.end());
    if (pieces == 1) t.x = sol.x;
  }
  if (out.solution.converged) out.solution.message = "every homotopy converged";
  detail::read_events<FesdMpcc<S>::ny, FesdMpcc<S>::nsw, S::nu, 2 * S::nq>(out.points, fesd.stages, out.element_lengths,
                                                                          out.frozen_phases, out.switch_points);
  out.trajectory = recover_trajectory<S>(system, out.points, fesd.stages);
  return out;
}

}  // namespace saltus::timefreezing
