// A user's own OCP solved and analysed through the installed headers (puck.hpp): discovery of the
// contact schedule by the time-freezing homotopy, the exact reference by the mode-schedule
// refinement (re-simulated by the event-driven simulator), then the library's analysis of it
// (jump gains, an LQR tracking design, its stability check, 20 perturbed closed-loop runs).
// Checks the figures a user relies on and prints the reports. Links puck.cpp.
#include "puck.hpp"

#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/refinement/refinement_io.hpp>

#include <cstdio>
#include <iostream>

int main() {
  using namespace saltus;
  using namespace saltus::timefreezing;
  const Puck puck;
  const TimeFreezingSystem<Puck> system(puck, /*auxiliary acceleration a_n=*/30.0);
  FesdOptions grid;  // 10 control intervals of 3 finite elements, Radau IIA n_s = 2
  grid.grid.control_intervals = 10;
  grid.grid.finite_elements = 3;
  grid.grid.horizon = 2.0;
  grid.clock.constraint = ClockConstraint::Terminal;  // the physical time ends at T = 2 s
  grid.clock.physical_horizon = 2.0;
  grid.clock.speed_of_time_max = 5.0;
  grid.bounds.control_lower = Eigen::VectorXd::Constant(2, -15.0);
  grid.bounds.control_upper = Eigen::VectorXd::Constant(2, 15.0);
  MpccSolverOptions solver;
  solver.homotopy.relaxation = MpccSolverOptions::Relaxation::Penalty;
  solver.ipopt.tol = 1e-8;
  const Vec<2> q0(0.0, 1.0), v0(0.0, 0.0);

  // 1. Discovery: the homotopy until its contact schedule settles.
  const DiscoveryResult<Puck> discovery = discover_schedule(puck, system, PuckToTheMark{}, q0, v0, grid, solver);
  if (!discovery.schedule_found) {
    std::printf("discovery: %s\n", discovery.message.c_str());
    return 1;
  }
  // 2. The exact reference: the smooth multi-phase OCP on that schedule.
  OcpHorizon<Puck> horizon;
  horizon.x0 << q0, v0;
  horizon.final_time = 2.0;
  horizon.control_lower = grid.bounds.control_lower;
  horizon.control_upper = grid.bounds.control_upper;
  const RefinementResult<Puck> refined =
      refine_schedule(puck, PuckToTheMark{}, horizon, discovery.discovered.guess, RefinementOptions{});
  std::printf("%s\n", to_json(puck, refined).dump(2).c_str());
  // 3. The analysis of the refined reference.
  ReferenceAnalysisOptions<Puck> options;
  options.monte_carlo.runs = 20;
  const auto analysis = analyse_reference(puck, refined.trajectory, SimulationOptions{}, options);
  std::printf("%s\n", to_json(analysis).dump(2).c_str());

  int failures = 0;
  const auto expect = [&](bool ok, const char* what) {
    if (!ok) std::printf("optimal_landing: %s does not hold\n", what);
    failures += ok ? 0 : 1;
  };
  expect(refined.converged && refined.stage == "refined", "the refinement converged");
  expect(refined.mode_validity_violation <= 1e-9, "mode validity <= 1e-9");
  expect(refined.phase_resim_max_error <= 1e-6, "per-phase re-simulation <= 1e-6");
  expect(!refined.trajectory.events.empty() && refined.trajectory.events[0].impact(), "the reference lands");
  expect(analysis.completed(), "every analysis stage completed");
  std::printf("optimal_landing: relaxed objective %.6g, refined %.6g, mode validity %.1e, re-simulation %.1e, %s\n",
              discovery.relaxed.solution.objective, refined.objective, refined.mode_validity_violation,
              refined.phase_resim_max_error,
              analysis.stability ? (analysis.stability->verdict == StabilityVerdict::Stable ? "stable" : "not shown stable")
                                 : "no verdict");
  return failures == 0 ? 0 : 1;
}
