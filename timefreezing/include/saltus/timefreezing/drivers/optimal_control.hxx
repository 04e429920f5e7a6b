// The definitions of the time-freezing optimal-control drivers (declared in optimal_control.hpp).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hxx>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/drivers/simulate.hxx>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

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
/// samples around the landing were compared across the jump (measured: 0.69 in the box's vertical
/// velocity at t = 0.3 on an optimum of the plank-box short landing whose impact was absorbed,
/// docs/decisions/fesd-composed-kinematics.md).
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

template <Scene S, class Problem>
TimeFreezingOcpResult<S> read_solution(const Problem& problem, MpccSolution solution, const FesdOptions& fesd);

/// Solves `problem` from `start` and reads the discrete solution, its events and its reference.
template <Scene S, class Problem>
TimeFreezingOcpResult<S> solve_and_read(const Problem& problem, const MpccStart& start, const FesdOptions& fesd,
                                        const MpccSolverOptions& solver) {
  return read_solution<S>(problem, solve_mpcc(problem, start, solver), fesd);
}

/// The discrete solution of `problem` at `solution`, its events, its reference and its trajectory.
template <Scene S, class Problem>
TimeFreezingOcpResult<S> read_solution(const Problem& problem, MpccSolution solution, const FesdOptions& fesd) {
  TimeFreezingOcpResult<S> out;
  out.solution = std::move(solution);
  const auto pts = problem.points(out.solution.x);
  out.points.assign(pts.begin(), pts.end());
  read_events<FesdMpcc<S>::ny, FesdMpcc<S>::nsw, S::nu, 2 * S::nq>(out.points, fesd.grid.stages, out.element_lengths,
                                                                  out.frozen_phases, out.switch_points);
  out.reference = recover_reference<S>(out.points, fesd.grid.stages);
  out.trajectory = recover_trajectory<S>(problem.system(), out.points, fesd.grid.stages);
  align_impact_samples(out.reference, out.trajectory);
  return out;
}
}  // namespace detail

template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp(const TimeFreezingSystem<S>& system, const Ocp& ocp, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, const FesdOptions& fesd,
                                                 const MpccSolverOptions& solver) {
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point(start.x);
  return detail::solve_and_read<S>(problem, start, fesd, solver);
}

template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_from_guess(const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                                            const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                            const FesdOptions& fesd, const MotionGuess& guess,
                                                            const MpccSolverOptions& solver) {
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point_from_guess(start.x, guess);
  return detail::solve_and_read<S>(problem, start, fesd, solver);
}

template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_by_continuation(const TimeFreezingSystem<S>& system,
                                                                 const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                                 const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                                 const FesdOptions& fesd,
                                                                 const MpccSolverOptions& solver) {
  SALTUS_REQUIRE(!continuation.empty(), "solve_time_freezing_ocp_by_continuation: the continuation is empty");
  MpccSolverOptions one_step = solver;
  one_step.homotopy.max_steps = 1;
  one_step.polish.enabled = false;
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
