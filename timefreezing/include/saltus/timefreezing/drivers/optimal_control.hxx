// The definitions of the time-freezing optimal-control drivers (declared in optimal_control.hpp).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hxx>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/drivers/simulate.hxx>
#include <saltus/timefreezing/recovery/recover_reference.hxx>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

namespace detail {
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
  out.trajectory = recover_trajectory<S>(problem.system(), out.points, fesd.grid.stages);
  out.reference = recover_reference<S>(out.trajectory, out.points, fesd.grid.stages);
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

namespace detail {
/// Where a continuation on the OCP's data ended: the start of the next solve (the last stage's
/// primal and dual solution), the stages' relaxed steps, and why it stopped early ("" when not).
struct ContinuationRun {
  MpccStart start;
  std::vector<MpccHomotopyStep> steps;
  int iterations = 0;
  double seconds = 0.0;
  std::string interrupted;
};

/// One relaxed NLP per stage of `continuation` at the solver's sigma_0 (no polish), in order, each
/// warm-started from the one before, the first from the initial state at every stage point; stops
/// at the first stage Ipopt does not solve. One progress line per stage when `progress` is set.
template <Scene S, class Ocp>
ContinuationRun run_continuation(const TimeFreezingSystem<S>& system, const std::vector<Ocp>& continuation,
                                 const Vec<S::nq>& q0, const Vec<S::nq>& v0, const FesdOptions& fesd,
                                 const MpccSolverOptions& solver, std::ostream* progress) {
  SALTUS_REQUIRE(!continuation.empty(), "the continuation is empty");
  MpccSolverOptions one_step = solver;
  one_step.homotopy.max_steps = 1;
  one_step.polish.enabled = false;
  ContinuationRun run;
  for (std::size_t c = 0; c < continuation.size(); ++c) {
    const FesdMpcc<S, Ocp> stage(system, continuation[c], q0, v0, fesd);
    if (c == 0) {
      run.start.x.resize(stage.variable_count());
      stage.initial_point(run.start.x);
    }
    const MpccSolution r = solve_mpcc(stage, run.start, one_step);
    for (MpccHomotopyStep st : r.steps) run.steps.push_back(st);
    run.iterations += r.ipopt_iterations;
    run.seconds += r.seconds;
    if (progress)
      *progress << "continuation stage " << c + 1 << " of " << continuation.size() << ": "
                << (r.steps.empty() ? std::string("no solve") : r.steps.back().ipopt_status) << ", "
                << r.ipopt_iterations << " iterations, " << r.seconds << " s, objective " << r.objective << "\n";
    run.start = MpccStart{r.x, r.constraint_multipliers, r.bound_multipliers_lower, r.bound_multipliers_upper};
    if (r.steps.empty() || !r.steps.back().ipopt_succeeded) {
      run.interrupted = "continuation stopped at stage " + std::to_string(c + 1) + " of " +
                        std::to_string(continuation.size()) + " (" +
                        (r.steps.empty() ? std::string("no solve") : r.steps.back().ipopt_status) + "); ";
      break;
    }
  }
  return run;
}
}  // namespace detail

template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_by_continuation(const TimeFreezingSystem<S>& system,
                                                                 const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                                 const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                                 const FesdOptions& fesd,
                                                                 const MpccSolverOptions& solver) {
  SALTUS_REQUIRE(!continuation.empty(), "solve_time_freezing_ocp_by_continuation: the continuation is empty");
  detail::ContinuationRun run = detail::run_continuation<S>(system, continuation, q0, v0, fesd, solver, solver.progress);
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  TimeFreezingOcpResult<S> out = detail::solve_and_read<S>(problem, run.start, fesd, solver);
  out.continuation_steps = std::move(run.steps);
  out.solution.ipopt_iterations += run.iterations;
  out.solution.seconds += run.seconds;
  out.solution.message = run.interrupted + out.solution.message;
  return out;
}

}  // namespace saltus::timefreezing
