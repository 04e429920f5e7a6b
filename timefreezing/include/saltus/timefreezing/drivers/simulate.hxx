// The definition of simulate_time_freezing (declared in simulate.hpp).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hxx>
#include <saltus/timefreezing/drivers/simulate.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace saltus::timefreezing {

template <Scene S, class InputLaw>
TimeFreezingSimulation<S> simulate_time_freezing(const TimeFreezingSystem<S>& system, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, FesdOptions fesd, const InputLaw& law,
                                                 const MpccSolverOptions& solver,
                                                 SimulationSplit split) {
  constexpr int nq = S::nq;
  // Checked here too: the split below divides by them before FesdMpcc would see them.
  SALTUS_REQUIRE(fesd.grid.control_intervals >= 1, "FESD: control_intervals must be >= 1, got ", fesd.grid.control_intervals);
  SALTUS_REQUIRE(std::isfinite(fesd.grid.horizon) && fesd.grid.horizon > 0.0, "FESD: the numerical horizon must be > 0, got ",
                 fesd.grid.horizon);
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
  out.trajectory = recover_trajectory<S>(system, out.points, fesd.grid.stages);
  return out;
}

}  // namespace saltus::timefreezing
