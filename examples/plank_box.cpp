// The plank-box (thesis appendix F): an actuated box lowered flat onto a compliant plank. Both
// bottom corners touch at the same instant (a planned simultaneous impact with a singular
// Delassus matrix: two contacts, redundant tangentially), the box sticks and the plank rocks on
// its spring. The box is held by a force slightly below its weight, so it descends at 2 m/s^2.
//
// `plank_box --json` instead solves the plank-box's flagship OCP (scenes/plank_box_landing.hpp):
// land flat, slide, lift off and stop above the plank's far end, minimising the integral of u'u;
// prints the report of ocp_report.hpp, progress lines (one per homotopy step) on stderr; exit
// status 0 only when the reference is refined (converged and exact). The reference is then analysed (analyse_reference,
// saltus/sensitivity/analysis/reference_analysis.hpp; the report's "analysis"): its re-simulation's
// jump gains (conewise at the flat landing), an LQR tracking design along it with its stability
// check (scenes/plank_box_tracking.hpp), and 200 perturbed closed-loop runs. The analysis's outcome
// does not change the exit status; its failures are reported in it. The optimisation has two
// stages: discovery (refinement/discovery.hpp: the time-freezing homotopy run until the contact
// schedule read off consecutive relaxed solutions settles; key "discovery") and the
// mode-schedule refinement (refinement.hpp), which makes the reference exact: that schedule, the
// smooth multi-phase OCP on the plank-box's own flows, guards and jump maps, its re-simulations. Keys "stage", "relaxed_objective",
// "discovery_seconds", "refinement_seconds", "schedule", "schedule_edits",
// "mode_validity_violation", "phase_resim_max_error" and "refinement" (refinement_io.hpp); when
// the refinement converged, the analysis is of the refined reference and "objective" its cost,
// and the refined reference's trajectory and forces go to report/plank_box_flat_landing/
// (report_files.hpp), where the main job also puts that JSON as report.json.
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/refinement_io.hpp>
#include "scenes/all_scenes.hpp"
#include "scenes/plank_box_landing.hpp"
#include "scenes/plank_box_tracking.hpp"
#include "ocp_report.hpp"
#include "report_files.hpp"

#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>

namespace {

int optimal_flat_landing() {
  using namespace saltus;
  using namespace saltus::timefreezing;
  using Ocp = scenes::PlankBoxFlatLanding;
  const scenes::PlankBox scene{};
  MpccSolverOptions solver = Ocp::solver();
  solver.progress = &std::cerr;
  DiscoveryOptions discovery_options;
  discovery_options.progress = &std::cerr;
  const DiscoveryResult<scenes::PlankBox> discovery =
      discover_schedule(scene, Ocp::system(), Ocp{}, Ocp::q0(), Ocp::v0(), Ocp::grid(), solver, discovery_options);
  const auto& r = discovery.relaxed;
  const Ocp::Feasibility f = Ocp::feasibility(r.points);
  std::optional<PolishResult<scenes::PlankBox>> resim;
  auto j = examples::ocp_report(scene, r, {f.path_violation, f.path_violation > 1e-6 ? "theta - phi = 0" : "", f.target_error},
                                &resim);
  j["relaxed_objective"] = r.solution.objective;
  j["discovery_seconds"] = discovery.seconds;
  j["discovery"] = to_json(discovery);
  j["stage"] = "discovery (" + discovery.message + ")";
  std::optional<RefinementResult<scenes::PlankBox>> refined;
  if (discovery.schedule_found) {
    try {
      RefinementOptions options = Ocp::refinement();
      options.progress = &std::cerr;
      refined = refine_schedule(scene, Ocp{}, Ocp::refinement_horizon(), discovery.discovered.guess, options);
      const nlohmann::ordered_json rj = to_json(scene, *refined);
      for (const char* key : {"stage", "schedule", "schedule_edits", "mode_validity_violation", "phase_resim_max_error",
                              "refinement_seconds"})
        j[key] = rj[key];
      j["refinement"] = rj;
      j["refinement"]["extraction_notes"] = to_json(discovery.discovered);
      if (refined->converged) j["objective"] = refined->objective;
    } catch (const Error& e) {
      j["stage"] = std::string("refinement (") + e.what() + ")";
    }
  }
  const HybridTrajectory<scenes::PlankBox>* reference =
      refined && refined->converged ? &refined->trajectory : (resim ? &resim->trajectory : nullptr);
  if (refined && refined->converged) {  // report/plank_box_flat_landing/ (stdout carries the JSON report)
    examples::write_scene_trajectory(scene, refined->trajectory, "plank_box_flat_landing", 0.005, stderr);
    examples::write_scene_forces(scene, refined->trajectory, "plank_box_flat_landing", 0.005, stderr);
  }
  if (reference) {
    ReferenceAnalysisOptions<scenes::PlankBox> analysis = scenes::plank_box_tracking(200);
    analysis.progress = &std::cerr;
    // Every run's deviation and its first-order prediction at 60 times (the report's figure).
    const double t0 = reference->t_begin(), T = reference->t_end();
    for (int k = 1; k <= 60; ++k) analysis.monte_carlo.deviation_times.push_back(k == 60 ? T : t0 + (T - t0) * k / 60.0);
    j["analysis"] = to_json(analyse_reference(scene, *reference, SimulationOptions{}, analysis));
  }
  std::cout << j.dump(2) << "\n";
  return refined && refined->stage == "refined" ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace saltus;
  if (argc > 1 && std::strcmp(argv[1], "--json") == 0) return optimal_flat_landing();
  using PB = scenes::PlankBox;
  PB plank_box;  // parameters and their sources: scenes/plank_box.hpp
  const Vec<8> x0 = plank_box.flat_state(0.6, 0.05);  // box centre 0.6 m along, bottom 5 cm above the plank
  auto hold = open_loop<PB>([&](double) { return plank_box.lowering_input(2.0); });  // weight - 2 N

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  Simulator<PB> simulator(plank_box, options);
  const auto traj = simulator.run(x0, 0.0, 1.0, hold);

  std::printf("plank-box: box lowered flat onto the plank\n");
  print_events(plank_box, traj);
  const auto& landing = traj.events.at(0);
  std::printf("  landing: %zu guards at once, box velocity after (%.3e, %.3e) m/s, plank rate %.4f rad/s\n",
              landing.guards().size(), landing.x_plus[4], landing.x_plus[5], landing.x_plus[7]);
  examples::write_scene_trajectory(plank_box, traj, "plank_box", 0.005);  // report/plank_box/
  examples::write_scene_forces(plank_box, traj, "plank_box", 0.005);
  return landing.guards().size() == 2 ? 0 : 1;
}
