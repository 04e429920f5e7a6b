// The guiding example of the time-freezing paper (Examples 1-3): a unit point mass dropped from
// height 1 onto a frictionless table, pushed sideways by u1 = 7 and, from t = 1, lifted by
// u2 = 2 g (t - 1). It lands at t = sqrt(2/g) (inelastic impact), slides, and lifts off at t = 1.5
// when the normal force m g - u2 reaches zero: a state-input guard.
//
// `guiding_example --json` instead solves a small time-freezing OCP with the same mass on a table
// with friction (mu = 0.2): from rest at (0, 1) to rest at x = 3 on the table at T = 2 s,
// minimising the integral of u'u, |u_i| <= 20 (FESD, N = 10, N_fe = 3, n_s = 2; penalty homotopy,
// Ipopt tol 1e-8), re-simulates its recovered reference with the event-driven simulator and
// prints {"converged", "complementarity", "objective", "homotopy_steps", "ipopt_iterations",
// "solve_seconds", "resim_max_error", "resim_events", "impacts", "touchdowns"} (progress lines on
// stderr): resim_events counts the events of the re-simulation, impacts the frozen runs, touchdowns
// the gap's switch points into contact. Then the mode-schedule refinement (the second stage): the
// schedule read off the relaxed solution (extract_schedule), the smooth multi-phase OCP on the
// point mass's own flows, guards and jump maps (refine_schedule), its per-phase and open-loop
// re-simulations: "stage" ("refined" or where it stopped), "relaxed_objective",
// "discovery_seconds", "refinement_seconds", "schedule", "schedule_edits",
// "mode_validity_violation", "phase_resim_max_error" and the whole result under "refinement"
// (refinement_io.hpp); "objective" is then the refined one.
#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/refinement_io.hpp>
#include "report_files.hpp"
#include "scenes/all_scenes.hpp"
#include "scenes/time_freezing_examples.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

namespace {

/// The second stage on the relaxed solution r: schedule extraction, refinement, the keys of the
/// file comment.
void refine(const saltus::scenes::PointMass& mass, const saltus::timefreezing::TimeFreezingOcpResult<saltus::scenes::PointMass>& r,
            nlohmann::ordered_json& j) {
  using namespace saltus::timefreezing;
  using Case = saltus::scenes::PointMassToTheTarget;
  j["relaxed_objective"] = r.solution.objective;
  j["discovery_seconds"] = r.solution.seconds;
  if (!r.converged()) {
    j["stage"] = "discovery (the time-freezing homotopy did not converge)";
    return;
  }
  try {
    const ExtractedSchedule<saltus::scenes::PointMass> discovered = extract_schedule(mass, r.trajectory);
    RefinementOptions options;
    options.progress = &std::cerr;
    const RefinementResult<saltus::scenes::PointMass> refined =
        refine_schedule(mass, Case{}, Case::refinement_horizon(), discovered.guess, options);
    const nlohmann::ordered_json rj = to_json(mass, refined);
    for (const char* key : {"stage", "schedule", "schedule_edits", "mode_validity_violation", "phase_resim_max_error",
                            "refinement_seconds"})
      j[key] = rj[key];
    if (refined.converged) j["objective"] = refined.objective;
    j["refinement"] = rj;
    j["refinement"]["extraction_notes"] = to_json(discovered);
  } catch (const saltus::Error& e) {
    j["stage"] = std::string("refinement (") + e.what() + ")";
  }
}

int time_freezing_ocp() {
  using namespace saltus;
  using namespace saltus::timefreezing;
  using Case = scenes::PointMassToTheTarget;
  MpccSolverOptions solver = Case::solver();
  solver.progress = &std::cerr;
  const auto r = solve_time_freezing_ocp(Case::system(), Case{}, Case::q0(), Case::v0(), Case::grid(), solver);
  const scenes::PointMass mass(Case::parameters());
  nlohmann::ordered_json j;
  j["converged"] = r.converged();
  j["complementarity"] = r.solution.complementarity;
  j["objective"] = r.solution.objective;
  j["homotopy_steps"] = r.solution.steps.size();
  j["ipopt_iterations"] = r.solution.ipopt_iterations;
  j["solve_seconds"] = r.solution.seconds;
  // The re-simulation of the recovered reference (r.reference: the samples of r.trajectory).
  try {
    const PolishResult<scenes::PointMass> resim = polish(mass, r.reference);
    j["resim_max_error"] = resim.state_distance;
    j["resim_events"] = resim.simulated_events;
  } catch (const Error& e) {
    j["resim_max_error"] = nullptr;
    j["resim_failure"] = e.what();
  }
  j["impacts"] = r.frozen_phases.size();
  j["touchdowns"] = [&] {
    int n = 0;
    for (const SwitchPoint& s : r.switch_points)
      if (s.switching_function == 0 && s.alpha_before > 0.5 && s.alpha_after < 0.5) ++n;
    return n;
  }();
  refine(mass, r, j);
  std::cout << j.dump(2) << "\n";
  return r.converged() && j["stage"] == "refined" ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace saltus;
  if (argc > 1 && std::strcmp(argv[1], "--json") == 0) return time_freezing_ocp();
  using Mass = scenes::PointMass;
  Mass mass;
  const double g = mass.parameters().gravity;
  auto thrust = open_loop<Mass>([g](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  options.breakpoints = {1.0};  // the thrust has a kink at t = 1
  Simulator<Mass> simulator(mass, options);
  const auto traj = simulator.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 2.0, thrust);

  std::printf("guiding example (time-freezing paper, Example 3)\n");
  print_events(mass, traj);
  // Closed form at t = 2: q1 = 3.5 t^2, v1 = 7 t; after lift-off q2 = g (t - 1.5)^3 / 3, v2 = g (t - 1.5)^2.
  const Vec<4> exact(14.0, g * 0.125 / 3.0, 14.0, g * 0.25);
  const double error = (traj.final_state() - exact).cwiseAbs().maxCoeff();
  std::printf("  impact at %.15f (closed form %.15f), lift-off at %.15f (closed form 1.5)\n", traj.events.at(0).t,
              std::sqrt(2 / g), traj.events.at(1).t);
  std::printf("  final state error against the closed form: %.2e\n", error);
  examples::write_scene_trajectory(mass, traj, "guiding_example", 0.01);  // report/guiding_example/
  examples::write_scene_forces(mass, traj, "guiding_example", 0.01);
  return error < 1e-8 ? 0 : 1;
}
