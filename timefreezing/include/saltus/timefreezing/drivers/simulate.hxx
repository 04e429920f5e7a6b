// The definition of simulate_time_freezing (declared in simulate.hpp).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hxx>
#include <saltus/timefreezing/drivers/simulate.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace saltus::timefreezing {

namespace detail {

/// One control interval's MPCC solved from (q, v), and its points.
template <Scene S>
struct SolvedInterval {
  MpccSolution solution;
  std::vector<typename FesdMpcc<S>::Point> points;
  int finite_elements = 0;
  double contact_side = 0.0;  ///< the contact-side weight it was solved with
};

template <Scene S, class InputLaw>
SolvedInterval<S> solve_interval(const TimeFreezingSystem<S>& system, const InputLaw& law, const Vec<S::nq>& q,
                                           const Vec<S::nq>& v, const FesdOptions& piece, const MpccSolverOptions& solver) {
  const FesdMpcc<S, InputLaw> problem(system, law, q, v, piece);
  SolvedInterval<S> out;
  out.solution = solve_mpcc(problem, solver);
  out.points = problem.points(out.solution.x);
  out.finite_elements = piece.grid.finite_elements;
  out.contact_side = piece.regularisation.contact_side;
  return out;
}

/// How far a contact's integrated gap (TimeFreezingSystem: g_i' = Theta J_n,i v from g_i = gap_i(q)
/// at the interval's start) descends over the interval's points below zero, or below its start
/// where that is below zero (>= 0) [the unit of the gaps]. The integrated gap stays put wherever
/// the collocation holds J_n v = 0 at the stage points (a frozen phase, a rest), so it sees the
/// complementarity's drift and not the collocation's own error of a gap nonlinear in q (Painleve's
/// rod turning on its sticking end: gap(q) 1.0e-7 below zero on 8 elements, its integrated gap
/// 4.7e-13).
template <Scene S, class Point>
double deepest_penetration(const std::vector<Point>& points) {
  double deepest = 0.0;
  if (points.empty()) return deepest;
  for (int i = 0; i < S::nc; ++i) {
    const int g = TimeFreezingSystem<S>::gap_state_index + i;
    const double floor = std::min(0.0, points.front().y[g]);
    for (const Point& p : points) deepest = std::max(deepest, floor - p.y[g]);
  }
  return deepest;
}

/// The largest step back of the physical clock between consecutive points (>= 0) [s]. The exact
/// clock never runs back (t' = Theta >= 0 in every region); a collocation element that holds two
/// modes (an impact's end and the rest after it, with Theta 0 at one stage and 0.91 at the other)
/// can, through Radau IIA's negative coefficient: the rod landing flat from 0.3 m without the
/// contact-side selection, its clock 1.4e-3 s back inside the impact's element, the positions
/// moving during the impact, the stop 1.7e-5 off.
template <Scene S, class Point>
double clock_reversal(const std::vector<Point>& points) {
  constexpr int t = TimeFreezingSystem<S>::clock_index;
  double back = 0.0;
  for (std::size_t k = 1; k < points.size(); ++k) back = std::max(back, points[k - 1].y[t] - points[k].y[t]);
  return back;
}

/// Whether at x = (q, v) a contact still approaches: gap <= 1e-4 m and J_n v < -1e-4 m/s
/// (recover_trajectory's default tolerances; FrozenPhase::cut).
template <Scene S>
bool impact_unfinished(const TimeFreezingSystem<S>& system, const Vec<2 * S::nq>& x) {
  const Vec<S::nq> q = x.template head<S::nq>(), v = x.template tail<S::nq>();
  const auto c = system.template switching_functions<double>(q, v);
  for (int i = 0; i < S::nc; ++i)
    if (c[3 * i] <= 1e-4 && c[3 * i + 1] < -1e-4) return true;
  return false;
}

/// The attempts of the fallback after the first (SimulationFallback). An interval that did not
/// converge: finer grids, then the contact-side selection toggled on the interval's grid and the
/// finer ones. One that converged with a flaw (a penetration: the gap's drift; or a clock
/// reversal): without the selection, the selection turned on, on the interval's grid and the finer
/// ones, only (without it a finer grid converged to wrong motions: the guiding example's interval
/// at tau = 0.5, q1 6.9e-4 off); with it, the finer grids. Rejected: the toggled selection before
/// the finer grids (the rod landing flat from 0.3 m then converged without the selection to an
/// impact 8e-3 off in v_x+).
inline std::vector<FesdOptions> fallback_attempts(const FesdOptions& piece, const SimulationFallback& fallback,
                                                  bool converged_with_flaw) {
  std::vector<FesdOptions> attempts;
  FesdOptions toggled = piece;
  toggled.regularisation.contact_side = piece.regularisation.contact_side > 0.0 ? 0.0 : fallback.contact_side_weight;
  const bool drift = converged_with_flaw && piece.regularisation.contact_side == 0.0;
  for (int toggle = drift ? 1 : 0; toggle < (converged_with_flaw && !drift ? 1 : 2); ++toggle)
    for (int r = toggle == 0 ? 1 : 0; r <= fallback.max_refinements; ++r) {  // not the first attempt itself
      FesdOptions attempt = toggle == 0 ? piece : toggled;
      attempt.grid.finite_elements <<= r;
      attempts.push_back(attempt);
    }
  return attempts;
}

/// solve_interval, and where it fails (no convergence, a penetration or a clock reversal) the
/// fallback's attempts in order: the first that succeeds; else the least bad (the converged attempt
/// whose flaws exceed their tolerances the least, else the first attempt), marked not converged.
/// `log` gets a line when the first attempt failed.
template <Scene S, class InputLaw>
SolvedInterval<S> solve_interval_with_fallback(const TimeFreezingSystem<S>& system, const InputLaw& law,
                                                         const Vec<S::nq>& q, const Vec<S::nq>& v, const FesdOptions& piece,
                                                         const MpccSolverOptions& solver, const SimulationFallback& fallback,
                                                         int interval, std::vector<std::string>& log) {
  // A converged attempt's penetration [m] and clock reversal [s] (depth infinite for one that did
  // not converge, or whose points are not finite). The larger of their ratios to their tolerances
  // ranks the attempts when none succeeds.
  struct Flaws {
    double depth, reversal;
  };
  const auto flaws_of = [&](const SolvedInterval<S>& s) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    if (!s.solution.converged) return Flaws{inf, 0.0};
    for (const auto& p : s.points)
      if (!p.y.allFinite()) return Flaws{inf, 0.0};
    return Flaws{deepest_penetration<S>(s.points), clock_reversal<S>(s.points)};
  };
  const auto worst = [&](const Flaws& f) {
    return std::max(f.depth / std::max(fallback.penetration_tolerance, 1e-300),
                    f.reversal / SimulationFallback::clock_reversal_tolerance);
  };
  const auto failure = [&](const Flaws& f) -> std::string {
    std::ostringstream text;
    text << std::setprecision(3);
    if (std::isinf(f.depth))
      text << "not converged";
    else if (f.depth > fallback.penetration_tolerance)
      text << "a contact penetrated by " << f.depth;
    else if (f.reversal > SimulationFallback::clock_reversal_tolerance)
      text << "the clock ran back by " << f.reversal << " s";
    return text.str();
  };
  SolvedInterval<S> first = solve_interval(system, law, q, v, piece, solver);
  const Flaws first_flaws = flaws_of(first);
  const std::string first_failure = failure(first_flaws);
  if (first_failure.empty() || !fallback.enabled) return first;
  double seconds = first.solution.seconds;
  int iterations = first.solution.ipopt_iterations;
  const auto describe = [&](const FesdOptions& o) {
    const bool on = o.regularisation.contact_side > 0.0;
    const bool as_given = on == (piece.regularisation.contact_side > 0.0);
    return std::to_string(o.grid.finite_elements) + " finite elements, contact-side selection " + (on ? "on" : "off") +
           (as_given ? " (as given)" : on ? " (turned on)" : " (turned off)");
  };
  SolvedInterval<S> best = first;
  double best_worst = worst(first_flaws);
  std::string best_attempt = "the first attempt", best_failure = first_failure;
  const std::vector<FesdOptions> attempts = fallback_attempts(piece, fallback, first.solution.converged);
  for (const FesdOptions& attempt : attempts) {
    if (solver.progress)
      *solver.progress << "simulate_time_freezing: fallback (" << first_failure << "): the interval again on "
                       << describe(attempt) << "\n";
    SolvedInterval<S> again = solve_interval(system, law, q, v, attempt, solver);
    seconds += again.solution.seconds;
    iterations += again.solution.ipopt_iterations;
    const Flaws flaws = flaws_of(again);
    if (failure(flaws).empty()) {
      again.solution.seconds = seconds;  // the interval's cost, the failed attempts included
      again.solution.ipopt_iterations = iterations;
      log.push_back("interval " + std::to_string(interval) + " (" + first_failure + "): solved on " + describe(attempt));
      return again;
    }
    if (worst(flaws) < best_worst) {
      best = std::move(again);
      best_worst = worst(flaws);
      best_failure = failure(flaws);
      best_attempt = describe(attempt) + " (" + best_failure + ")";
    }
  }
  best.solution.seconds = seconds;
  best.solution.ipopt_iterations = iterations;
  // A converged interval with a flaw is not a solution either; its own message would say converged.
  const std::string detail = best.solution.converged ? best_failure : best.solution.message;
  best.solution.converged = false;
  const std::string outcome = attempts.empty() ? "the fallback has no attempt for it (max_refinements = 0, selection on)"
                                               : "no attempt of the fallback succeeded";
  best.solution.message = first_failure + "; " + outcome + ", the run goes on from " + best_attempt + ": " + detail;
  log.push_back("interval " + std::to_string(interval) + " (" + first_failure + "): " + outcome + "; kept " + best_attempt);
  return best;
}

}  // namespace detail

template <Scene S, class InputLaw>
TimeFreezingSimulation<S> simulate_time_freezing(const TimeFreezingSystem<S>& system, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, FesdOptions fesd, const InputLaw& law,
                                                 const MpccSolverOptions& solver,
                                                 const TimeFreezingSimulationOptions& options) {
  const SimulationSplit split = options.split;
  constexpr int nq = S::nq;
  // Checked here too: the split below divides by them before FesdMpcc would see them.
  SALTUS_REQUIRE(fesd.grid.control_intervals >= 1, "FESD: control_intervals must be >= 1, got ", fesd.grid.control_intervals);
  SALTUS_REQUIRE(std::isfinite(fesd.grid.horizon) && fesd.grid.horizon > 0.0, "FESD: the numerical horizon must be > 0, got ",
                 fesd.grid.horizon);
  SALTUS_REQUIRE(options.fallback.max_refinements >= 0 && options.fallback.max_refinements <= 6,
                 "simulate_time_freezing: fallback.max_refinements must be in 0..6, got ", options.fallback.max_refinements);
  SALTUS_REQUIRE(options.fallback.penetration_tolerance >= 0.0,
                 "simulate_time_freezing: fallback.penetration_tolerance must be >= 0, got ",
                 options.fallback.penetration_tolerance);
  SALTUS_REQUIRE(std::isfinite(options.fallback.contact_side_weight) && options.fallback.contact_side_weight > 0.0,
                 "simulate_time_freezing: fallback.contact_side_weight must be finite and > 0, got ",
                 options.fallback.contact_side_weight);
  fesd.clock.constraint = ClockConstraint::None;
  fesd.clock.speed_of_time_max = 1.0;
  fesd.regularisation.speed_of_time = 0.0;
  fesd.bounds.control_lower = Eigen::VectorXd::Zero(S::nu);
  fesd.bounds.control_upper = Eigen::VectorXd::Zero(S::nu);
  TimeFreezingSimulation<S> out;
  const int pieces = split == SimulationSplit::WholeHorizon ? 1 : fesd.grid.control_intervals;
  FesdOptions piece = fesd;
  if (pieces > 1) {
    piece.grid.control_intervals = 1;
    piece.grid.horizon = fesd.grid.horizon / fesd.grid.control_intervals;
  }
  Vec<nq> q = q0, v = v0;
  double tau0 = 0.0, cost0 = 0.0;
  out.solution.converged = true;
  for (int k = 0; k < pieces; ++k) {
    // Which MPCC the progress lines that follow belong to (each restarts at step 0).
    if (solver.progress && pieces > 1)
      *solver.progress << "simulate_time_freezing: control interval " << k + 1 << " of " << pieces << "\n";
    const std::size_t logged = out.fallback_log.size();
    auto solved = split == SimulationSplit::PerControlInterval
                      ? detail::solve_interval_with_fallback(system, law, q, v, piece, solver, options.fallback, k,
                                                             out.fallback_log)
                      : detail::solve_interval(system, law, q, v, piece, solver);
    out.fallbacks += out.fallback_log.size() > logged && solved.solution.converged;
    // A contact-side selection that the fallback turned on and that solved the interval is kept for
    // the rest of the run (the drift it cured comes back in every later interval in contact); one
    // it turned off rescued that interval only (SimulationFallback, attempt 2).
    if (solved.solution.converged)
      piece.regularisation.contact_side = std::max(piece.regularisation.contact_side, solved.contact_side);
    out.finite_elements.push_back(solved.finite_elements);
    MpccSolution& sol = solved.solution;
    auto& pts = solved.points;
    for (auto& p : pts) {
      p.tau += tau0;
      p.interval += k;
      p.y[TimeFreezingSystem<S>::cost_index] += cost0;
    }
    out.points.insert(out.points.end(), pts.begin() + (k == 0 ? 0 : 1), pts.end());
    const auto& end = out.points.back().y;
    q = end.template head<nq>();
    v = end.template segment<nq>(nq);
    piece.clock.initial_time = end[TimeFreezingSystem<S>::clock_index];
    // The user's initial state was checked; a later interval starts where the previous one
    // ended, which may be below a contact by the discretisation's own drift (a frozen phase's gap
    // of -1e-5 under a relaxation, fesd_objective.hxx): not a user error.
    piece.bounds.gap_tolerance = std::numeric_limits<double>::infinity();
    cost0 = end[TimeFreezingSystem<S>::cost_index];
    tau0 += piece.grid.horizon;
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
  detail::read_events<FesdMpcc<S>::ny, FesdMpcc<S>::nsw, S::nu, 2 * S::nq>(out.points, fesd.grid.stages, out.element_lengths,
                                                                          out.frozen_phases, out.switch_points);
  for (FrozenPhase<2 * nq>& f : out.frozen_phases) f.cut = detail::impact_unfinished(system, f.x_plus);
  out.trajectory = recover_trajectory<S>(system, out.points, fesd.grid.stages);
  return out;
}

}  // namespace saltus::timefreezing
