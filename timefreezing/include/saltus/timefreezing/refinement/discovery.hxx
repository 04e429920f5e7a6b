// The definitions of the discovery stage (declared in discovery.hpp).
#pragma once

#include <saltus/timefreezing/drivers/optimal_control.hxx>
#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hxx>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <sstream>
#include <utility>

namespace saltus::timefreezing {

inline TrajectoryRecoveryOptions RelaxedContactReading::at(double sigma) const {
  TrajectoryRecoveryOptions o = recovery;
  o.gap_tolerance = std::min(gap_max, std::max(o.gap_tolerance, gap_per_sigma * sigma));
  o.velocity_tolerance = std::min(velocity_max, std::max(o.velocity_tolerance, velocity_per_sigma * sigma));
  return o;
}

inline void DiscoveryOptions::validate() const {
  SALTUS_REQUIRE(std::isfinite(reading.gap_per_sigma) && reading.gap_per_sigma >= 0.0,
                 "DiscoveryOptions::reading.gap_per_sigma must be finite and >= 0, got ", reading.gap_per_sigma);
  SALTUS_REQUIRE(std::isfinite(reading.velocity_per_sigma) && reading.velocity_per_sigma >= 0.0,
                 "DiscoveryOptions::reading.velocity_per_sigma must be finite and >= 0, got ", reading.velocity_per_sigma);
  SALTUS_REQUIRE(reading.gap_max > 0.0 && reading.velocity_max > 0.0, "DiscoveryOptions::reading: gap_max and velocity_max must be > 0, got ",
                 reading.gap_max, " and ", reading.velocity_max);
  SALTUS_REQUIRE(max_steps >= 1, "DiscoveryOptions::max_steps must be >= 1, got ", max_steps);
  SALTUS_REQUIRE(agreeing_steps >= 1, "DiscoveryOptions::agreeing_steps must be >= 1, got ", agreeing_steps);
}

namespace detail {

/// The step's record from a one-step solve of the homotopy.
inline DiscoveryStep discovery_step(int k, double sigma, const MpccSolution& solution) {
  DiscoveryStep step;
  step.index = k;
  step.sigma = sigma;
  step.complementarity = solution.complementarity;
  step.objective = solution.objective;
  step.ipopt_iterations = solution.ipopt_iterations;
  step.seconds = solution.seconds;
  step.ipopt_status = solution.steps.empty() ? std::string("no solve") : solution.steps.back().ipopt_status;
  return step;
}

inline void print_discovery_step(std::ostream* out, const DiscoveryStep& s) {
  if (out == nullptr) return;
  *out << "discovery step " << s.index << "  sigma " << s.sigma << "  compl " << s.complementarity << "  f " << s.objective
       << "  iter " << s.ipopt_iterations << "  " << s.ipopt_status << "  " << s.seconds << " s  schedule: "
       << (s.schedule.empty() ? "(none: " + s.extraction_error + ")" : s.schedule) << "\n";
}

}  // namespace detail

namespace detail {

/// The discovery's homotopy steps on `problem` from `start` (discover_schedule's loop); fills
/// `out.steps`, `relaxed`, `relaxed_reading`, `discovered`, `settled` and `message`.
template <Scene S, class Problem>
void run_discovery_steps(const S& scene, const Problem& problem, MpccStart start, const FesdOptions& fesd,
                         const MpccSolverOptions& solver, const DiscoveryOptions& options, DiscoveryResult<S>& out) {
  MpccSolverOptions one_step = solver;
  one_step.homotopy.max_steps = 1;
  one_step.polish.enabled = false;
  std::string previous;
  int agreeing = 0;
  double sigma = solver.homotopy.sigma_0;
  for (int k = 0; k < options.max_steps; ++k, sigma *= solver.homotopy.kappa) {
    one_step.homotopy.sigma_0 = sigma;
    MpccSolution solution = solve_mpcc(problem, start, one_step);
    DiscoveryStep step = discovery_step(k, sigma, solution);
    const bool solved = !solution.steps.empty() && solution.steps.back().ipopt_succeeded;
    if (!solved) {
      print_discovery_step(options.progress, step);
      out.steps.push_back(step);
      out.message = "Ipopt did not solve homotopy step " + std::to_string(k) + " (" + step.ipopt_status + ")";
      return;
    }
    start = MpccStart{solution.x, solution.constraint_multipliers, solution.bound_multipliers_lower,
                      solution.bound_multipliers_upper};
    out.relaxed = read_solution<S>(problem, std::move(solution), fesd);
    out.schedule_found = false;
    out.relaxed_reading = recover_trajectory<S>(problem.system(), out.relaxed.points, fesd.grid.stages, options.reading.at(sigma));
    try {
      out.discovered = extract_schedule(scene, out.relaxed_reading, options.extraction);
      out.schedule_found = true;
      step.schedule = describe(scene, out.discovered.guess.schedule);
    } catch (const Error& e) {
      step.extraction_error = e.what();
    }
    agreeing = step.schedule.empty() ? 0 : (step.schedule == previous ? agreeing + 1 : 1);
    previous = step.schedule;
    print_discovery_step(options.progress, step);
    out.steps.push_back(step);
    if (agreeing >= options.agreeing_steps) {
      out.settled = true;
      out.message = "the schedule settled: the same at " + std::to_string(agreeing) + " consecutive steps (last sigma " +
                    std::to_string(sigma) + ")";
      return;
    }
    if (out.relaxed.solution.converged) {
      out.message = "the homotopy converged at step " + std::to_string(k) + " before the schedule settled";
      return;
    }
  }
  out.message = "the schedule did not settle in " + std::to_string(options.max_steps) + " steps";
}

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace detail

template <Scene S, class Ocp>
DiscoveryResult<S> discover_schedule(const S& scene, const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                     const Vec<S::nq>& q0, const Vec<S::nq>& v0, const FesdOptions& fesd,
                                     const MpccSolverOptions& solver, const DiscoveryOptions& options) {
  options.validate();
  const auto clock = std::chrono::steady_clock::now();
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point(start.x);
  DiscoveryResult<S> out;
  detail::run_discovery_steps(scene, problem, std::move(start), fesd, solver, options, out);
  out.seconds = detail::seconds_since(clock);
  return out;
}

template <Scene S, class Ocp>
DiscoveryResult<S> discover_schedule_from_guess(const S& scene, const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                                const Vec<S::nq>& q0, const Vec<S::nq>& v0, const FesdOptions& fesd,
                                                const MotionGuess& guess, const MpccSolverOptions& solver,
                                                const DiscoveryOptions& options) {
  options.validate();
  const auto clock = std::chrono::steady_clock::now();
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point_from_guess(start.x, guess);
  DiscoveryResult<S> out;
  detail::run_discovery_steps(scene, problem, std::move(start), fesd, solver, options, out);
  out.seconds = detail::seconds_since(clock);
  return out;
}

template <Scene S, class Ocp>
DiscoveryResult<S> discover_schedule_by_continuation(const S& scene, const TimeFreezingSystem<S>& system,
                                                     const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                     const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                     const FesdOptions& fesd, const MpccSolverOptions& solver,
                                                     const DiscoveryOptions& options) {
  options.validate();
  SALTUS_REQUIRE(!continuation.empty(), "discover_schedule_by_continuation: the continuation is empty");
  const auto clock = std::chrono::steady_clock::now();
  detail::ContinuationRun run = detail::run_continuation<S>(system, continuation, q0, v0, fesd, solver, options.progress);
  DiscoveryResult<S> out;
  out.continuation_steps = std::move(run.steps);
  out.continuation_seconds = detail::seconds_since(clock);
  if (!run.interrupted.empty()) {
    out.message = run.interrupted + "no discovery step run";
    out.seconds = out.continuation_seconds;
    return out;
  }
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  detail::run_discovery_steps(scene, problem, std::move(run.start), fesd, solver, options, out);
  out.seconds = detail::seconds_since(clock);
  return out;
}

}  // namespace saltus::timefreezing
