// The time-freezing optimal-control drivers: build the FESD MPCC of an OCP, solve it by the MPCC
// homotopy (from the initial state, a guess, or a continuation on the OCP's data), and recover the
// result in physical time.
#pragma once

#include <saltus/timefreezing/drivers/simulate.hpp>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {


/// The result of solve_time_freezing_ocp.
template <Scene S>
struct TimeFreezingOcpResult {
  static constexpr int nx = 2 * S::nq;
  using Point = typename FesdMpcc<S>::Point;
  MpccSolution solution;       ///< converged, complementarity, objective, steps, iterations, seconds
  std::vector<Point> points;   ///< the discrete solution in numerical time
  std::vector<double> element_lengths;
  std::vector<FrozenPhase<nx>> frozen_phases;  ///< the impacts
  std::vector<SwitchPoint> switch_points;      ///< touchdowns, lift-offs, slip-stick
  ImportedReference<S> reference;              ///< recovered in physical time (recover_reference)
  /// Recovered in physical time (recover_trajectory); when not converged(), only a reading of the
  /// unconverged points, not a motion of the scene.
  HybridTrajectory<S> trajectory;
  /// solve_time_freezing_ocp_by_continuation: one relaxed NLP per continuation stage, in order
  /// (their iterations and seconds are included in solution.ipopt_iterations and seconds).
  std::vector<MpccHomotopyStep> continuation_steps;
  bool converged() const { return solution.converged; }
};


namespace detail {
// align_impact_samples' first part (its docstring): recover_trajectory's impacts that
// recover_reference has no event for, added to the reference.
template <Scene S>
void add_absorbed_impacts(ImportedReference<S>& ref, const HybridTrajectory<S>& traj) {
  if (ref.segment.size() != ref.t.size()) return;  // recover_reference writes every segment
  for (std::size_t e = 0; e < traj.events.size(); ++e) {
    if (!traj.events[e].impact()) continue;
    const double t = traj.events[e].t;
    const auto same = [t](double s) { return std::abs(s - t) <= 1e-12 * (1.0 + std::abs(t)); };
    if (std::any_of(ref.event_times.begin(), ref.event_times.end(), same)) continue;
    // x-: the last sample at the event's time
    std::size_t j = ref.size();
    for (std::size_t k = 0; k < ref.size(); ++k)
      if (same(ref.t[k])) j = k;
    if (j + 1 >= ref.size()) continue;  // no sample after it: nothing to mark as post-impact
    const double t_plus = x_plus_time(traj, e);
    std::size_t plus = j + 1;
    if (t_plus < ref.t[j + 1]) {  // x+ lies inside the element: a sample of its own
      ref.t.insert(ref.t.begin() + static_cast<std::ptrdiff_t>(plus), t_plus);
      ref.x.insert(ref.x.begin() + static_cast<std::ptrdiff_t>(plus), traj.events[e].x_plus);
      const typename ImportedReference<S>::Input u = ref.u[plus];
      const int segment = ref.segment[j];
      ref.u.insert(ref.u.begin() + static_cast<std::ptrdiff_t>(plus), u);
      ref.segment.insert(ref.segment.begin() + static_cast<std::ptrdiff_t>(plus), segment);
    }
    for (std::size_t k = plus; k < ref.size(); ++k) ++ref.segment[k];
    ref.event_times.insert(std::upper_bound(ref.event_times.begin(), ref.event_times.end(), ref.t[j]), ref.t[j]);
  }
}

/// The x+ sample of each of recover_reference's events set to the x+ of recover_trajectory's
/// impact event at the same time, at the time x+ belongs to (x_plus_time), where there is one:
/// recover_reference takes x+ at the end of the frozen run, recover_trajectory at the end of the
/// impact when the run ended before it (recover_trajectory's docstring), and the re-simulation
/// (polish()) compares each sample with the simulated state at the sample's time.
/// Also: an impact of recover_trajectory at a time where recover_reference has no event (an impact
/// absorbed into a flowing element: no frozen run, so recover_reference's samples pass through it
/// as flow) becomes an event of the reference: x- is the last sample at the event's time (the
/// element's start), x+ the trajectory's x+ at x_plus_time, inserted as a sample of the next
/// segment (with the input of the sample after it, the element's interval); when x+ falls on the
/// next sample's time, that sample (the element's end) starts the next segment as it is. Without it the re-simulation's impact had no partner in the reference, and its
/// samples around the landing were compared across the jump (measured: the plank-box short
/// landing's optimum under FesdOptions::composed_kinematics, measured 2026-12-02: 0.69 in the box's vertical velocity at t = 0.3).
template <Scene S>
void align_impact_samples(ImportedReference<S>& ref, const HybridTrajectory<S>& traj) {
  add_absorbed_impacts(ref, traj);
  for (std::size_t k = 0; k < ref.event_times.size(); ++k) {
    const double t = ref.event_times[k];
    std::size_t impact = traj.events.size();
    for (std::size_t e = 0; e < traj.events.size(); ++e)
      if (traj.events[e].impact() && std::abs(traj.events[e].t - t) <= 1e-12 * (1.0 + std::abs(t))) {
        impact = e;
        break;
      }
    if (impact == traj.events.size()) continue;
    for (std::size_t j = 0; j < ref.size(); ++j)
      if (ref.segment_of(j) == static_cast<int>(k) + 1) {
        const double t_plus = x_plus_time(traj, impact);
        const bool before_next = j + 1 >= ref.size() || t_plus < ref.t[j + 1];
        if (ref.t[j] == t && before_next) {
          ref.x[j] = traj.events[impact].x_plus;
          ref.t[j] = t_plus;
        }
        break;
      }
  }
}

/// Solves `problem` from `start` and reads the discrete solution, its events and its reference.
template <Scene S, class Problem>
TimeFreezingOcpResult<S> solve_and_read(const Problem& problem, const MpccStart& start, const FesdOptions& fesd,
                                        const MpccSolverOptions& solver) {
  TimeFreezingOcpResult<S> out;
  out.solution = solve_mpcc(problem, start, solver);
  const auto pts = problem.points(out.solution.x);
  out.points.assign(pts.begin(), pts.end());
  read_events<FesdMpcc<S>::ny, FesdMpcc<S>::nsw, S::nu, 2 * S::nq>(out.points, fesd.stages, out.element_lengths,
                                                                  out.frozen_phases, out.switch_points);
  out.reference = recover_reference<S>(out.points, fesd.stages);
  out.trajectory = recover_trajectory<S>(problem.system(), out.points, fesd.stages);
  align_impact_samples(out.reference, out.trajectory);
  return out;
}
}  // namespace detail

/// Solves the time-freezing OCP described by `ocp` (FesdMpcc's docstring lists what it may
/// provide) from (q0, v0) with FESD, by the MPCC homotopy, and recovers its reference in physical
/// time. Returns the result whether or not the homotopy converged (converged() says; the message
/// says why not). Throws InvalidArgument for bad options or states.
/// Solver settings, measured on the point mass landing and sliding to a target (N = 10, N_fe = 3):
/// the defaults (Scholtes, tol 1e-10) took 6368 Ipopt iterations; tol = 1e-8 with
/// relaxation = Penalty took 422 (two homotopy steps and the polish) and found the cheaper of
/// the two local optima (18.8 against 35.2). Known limit: at a touchdown inside an element the
/// gap's switching function is exactly 0, its multipliers vanish and cross-complementarity cannot
/// stop the active set from changing inside that element; such an impact is not a frozen run of
/// elements and recover_reference misses it (the re-simulation then differs by O(1)).
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp(const TimeFreezingSystem<S>& system, const Ocp& ocp, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, const FesdOptions& fesd,
                                                 const MpccSolverOptions& solver = {}) {
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point(start.x);
  return detail::solve_and_read<S>(problem, start, fesd, solver);
}

/// solve_time_freezing_ocp from a guess of the motion instead of the initial state at every stage
/// point: `guess(t)` -> Vec<2 nq> (q, v) at physical time t (FesdMpcc::initial_point_from_guess
/// says how the stage points, step functions and multipliers are set from it). A guess is a
/// second initialisation, e.g. a gait whose contact timing the user knows; the contact-implicit
/// setting is solve_time_freezing_ocp. Throws InvalidArgument as solve_time_freezing_ocp and for a
/// guess that is not finite.
template <Scene S, class Ocp, class Guess>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_from_guess(const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                                            const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                            const FesdOptions& fesd, const Guess& guess,
                                                            const MpccSolverOptions& solver = {}) {
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point_from_guess(start.x, guess);
  return detail::solve_and_read<S>(problem, start, fesd, solver);
}

/// A continuation on the OCP's data before the homotopy: the relaxed NLP at the first relaxation
/// parameter solver.sigma_0 is solved for each OCP of `continuation` in turn (one homotopy step
/// each, no polish), the first from FesdMpcc's initial point and each later one from the previous
/// one's primal-dual solution (the same Ocp type on the same grid: the problems have the same
/// variables, only bounds or data differ); then the whole homotopy runs on `ocp` from the last of
/// them. E.g. the hopper over three holes (scenes/hopper_holes.hpp): the holes grow from nothing
/// (hole level 1e-4) to their size while the relaxation is loose, so the iterates never face a
/// full hole across the straight path from the start to the target (without it: Ipopt's
/// Infeasible_Problem_Detected in the first step, the foot stopped at a hole's edge).
/// What can vary: the Ocp's own data (bounds of its path and terminal rows, targets, costs); the
/// grid and the control bounds are FesdOptions, one for all stages. Each stage is solved at
/// sigma_0 only (Penalty: rho_0). Its Ipopt solves are in continuation_steps, not in
/// solution.steps, and counted in solution.ipopt_iterations and seconds.
/// A continuation stage that Ipopt does not solve (its status in continuation_steps) ends the
/// continuation: the homotopy then starts from that stage's iterate (or from the last successful
/// one), and the result says so in solution.message. Throws InvalidArgument as
/// solve_time_freezing_ocp, and for an empty continuation.
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_by_continuation(const TimeFreezingSystem<S>& system,
                                                                 const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                                 const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                                 const FesdOptions& fesd,
                                                                 const MpccSolverOptions& solver = {}) {
  SALTUS_REQUIRE(!continuation.empty(), "solve_time_freezing_ocp_by_continuation: the continuation is empty");
  MpccSolverOptions one_step = solver;
  one_step.max_homotopy_steps = 1;
  one_step.polish = false;
  MpccStart start;
  std::vector<MpccHomotopyStep> steps;
  int iterations = 0;
  double seconds = 0.0;
  std::string interrupted;
  for (std::size_t c = 0; c < continuation.size(); ++c) {
    const FesdMpcc<S, Ocp> stage(system, continuation[c], q0, v0, fesd);
    if (c == 0) {
      start.x.resize(stage.variable_count());
      stage.initial_point(start.x);
    }
    const MpccSolution r = solve_mpcc(stage, start, one_step);
    for (MpccHomotopyStep st : r.steps) steps.push_back(st);
    iterations += r.ipopt_iterations;
    seconds += r.seconds;
    if (solver.progress) *solver.progress << "continuation stage " << c + 1 << " of " << continuation.size() << " done\n";
    start.x = r.x;
    start.constraint_multipliers = r.constraint_multipliers;
    start.bound_multipliers_lower = r.bound_multipliers_lower;
    start.bound_multipliers_upper = r.bound_multipliers_upper;
    if (r.steps.empty() || !r.steps.back().ipopt_succeeded) {
      interrupted = "continuation stopped at stage " + std::to_string(c + 1) + " of " + std::to_string(continuation.size()) +
                    " (" + (r.steps.empty() ? std::string("no solve") : r.steps.back().ipopt_status) + "); ";
      break;
    }
  }
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  TimeFreezingOcpResult<S> out = detail::solve_and_read<S>(problem, start, fesd, solver);
  out.continuation_steps = std::move(steps);
  out.solution.ipopt_iterations += iterations;
  out.solution.seconds += seconds;
  out.solution.message = interrupted + out.solution.message;
  return out;
}

}  // namespace saltus::timefreezing
