// The optimise-then-analyse pipeline from Python, on the OCP the scene library compiles
// (scenes/time_freezing_examples.hpp, PointMassToTheTarget: the point mass with friction from rest
// at (0, 1) m to rest on the table at x = 3 m at T = 2 s, minimising the integral of u'u): the
// time-freezing homotopy discovers the contact schedule, the mode-schedule refinement makes the
// reference exact, and the refined reference comes back as a PointMassTrajectory that jump_gains,
// linearise and tracking analyse. The plank-box flat landing and the hopper over its holes run the
// whole chain (discovery, refinement, analyse_reference) as their C++ programs do: the hopper's is the
// scene library's run_hopper_chain (scenes/hopper_holes_refinement.hpp, saltus_hopper_refinement),
// the code of `hopper --json`. The solver's progress lines reach Python: a callable gets each line, or
// else the logging module's logger "saltus" (level INFO).
#include "common.hpp"
#include "scenes/hopper_holes_refinement.hpp"
#include "scenes/hopper_tracking.hpp"
#include "scenes/plank_box_landing.hpp"
#include "scenes/plank_box_tracking.hpp"
#include "scenes/time_freezing_examples.hpp"

#include <saltus/python/progress.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/refinement/discovery.hpp>

#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/refinement_io.hpp>

#include <memory>
#include <optional>
#include <ostream>

namespace saltus::python {

namespace {

/// A refined reference handed to Python: its scene, the simulation options it is re-simulated and
/// analysed with, breakpoints at the refinement's element times (the optimal input is piecewise
/// smooth, with jumps at the element boundaries), and its name.
template <Scene S>
std::shared_ptr<PyTrajectory<S>> refined_reference(const S& scene, SimulationOptions options,
                                                    const std::vector<double>& element_times, std::string name,
                                                    HybridTrajectory<S> trajectory) {
  auto reference = std::make_shared<PyTrajectory<S>>();
  reference->scene = std::make_shared<const S>(scene);
  reference->options = std::move(options);
  reference->options.breakpoints = element_times;
  reference->name = std::move(name);
  reference->trajectory = std::move(trajectory);
  return reference;
}

py::dict point_mass_to_the_target(py::object progress) {
  using namespace timefreezing;
  using Case = scenes::PointMassToTheTarget;
  PythonLines lines(progress_sink(std::move(progress)));
  std::ostream out(&lines);
  py::dict result;
  const scenes::PointMass mass(Case::parameters());
  std::optional<TimeFreezingOcpResult<scenes::PointMass>> relaxed;
  std::optional<RefinementResult<scenes::PointMass>> refined;
  std::string stage;
  {
    py::gil_scoped_release release;
    MpccSolverOptions solver = Case::solver();
    solver.progress = &out;
    relaxed.emplace(solve_time_freezing_ocp(Case::system(), Case{}, Case::q0(), Case::v0(), Case::grid(), solver));
    if (relaxed->converged()) {
      const ExtractedSchedule<scenes::PointMass> discovered = extract_schedule(mass, relaxed->trajectory);
      RefinementOptions options;
      options.progress = &out;
      refined.emplace(refine_schedule(mass, Case{}, Case::refinement_horizon(), discovered.guess, options));
      stage = refined->stage;
    } else {
      stage = "discovery (the time-freezing homotopy did not converge)";
    }
    out.flush();
  }
  lines.rethrow();
  result["stage"] = stage;
  result["relaxed_objective"] = relaxed->solution.objective;
  result["complementarity"] = relaxed->solution.complementarity;
  result["homotopy_steps"] = relaxed->solution.steps.size();
  result["ipopt_iterations"] = relaxed->solution.ipopt_iterations;
  result["discovery_seconds"] = relaxed->solution.seconds;
  if (refined) {
    const auto j = to_json(mass, *refined);
    result["schedule"] = j["schedule"].get<std::string>();
    result["converged"] = refined->converged;
    result["objective"] = refined->objective;
    result["event_times"] = refined->event_times;
    result["mode_validity_violation"] = refined->mode_validity_violation;
    result["phase_resim_max_error"] = refined->phase_resim_max_error;
    result["refinement_seconds"] = refined->seconds;
    result["refinement_json"] = j.dump();
    result["reference"] = refined_reference(mass, precise_simulation(), refined->element_times,
                                            "point mass to the target (refined)", refined->trajectory);
  } else {
    result["converged"] = false;
  }
  return result;
}

/// The plank-box flat landing (scenes/plank_box_landing.hpp) optimised and analysed as
/// `build/examples/plank_box --json` does it: discovery, refinement with up to `max_edits` schedule
/// edits, then analyse_reference with the scene library's LQR design and `runs` Monte Carlo runs.
py::dict plank_box_flat_landing(py::object progress, int max_edits, int runs) {
  using namespace timefreezing;
  using Ocp = scenes::PlankBoxFlatLanding;
  SALTUS_REQUIRE(max_edits >= 0, "max_edits must be >= 0, got ", max_edits);
  SALTUS_REQUIRE(runs >= 1, "runs must be >= 1, got ", runs);
  PythonLines lines(progress_sink(std::move(progress)));
  std::ostream out(&lines);
  const scenes::PlankBox scene{};
  std::optional<DiscoveryResult<scenes::PlankBox>> discovery;
  std::optional<RefinementResult<scenes::PlankBox>> refined;
  std::optional<nlohmann::ordered_json> analysis;
  {
    py::gil_scoped_release release;
    MpccSolverOptions solver = Ocp::solver();
    solver.progress = &out;
    DiscoveryOptions discovery_options;
    discovery_options.progress = &out;
    discovery.emplace(
        discover_schedule(scene, Ocp::system(), Ocp{}, Ocp::q0(), Ocp::v0(), Ocp::grid(), solver, discovery_options));
    if (discovery->schedule_found) {
      RefinementOptions options = Ocp::refinement();
      options.progress = &out;
      options.edits.max_edits = max_edits;
      refined.emplace(refine_schedule(scene, Ocp{}, Ocp::refinement_horizon(), discovery->discovered.guess, options));
    }
    if (refined && refined->converged) {
      ReferenceAnalysisOptions<scenes::PlankBox> a = scenes::plank_box_tracking(runs);
      a.progress = &out;
      a.monte_carlo.threads = 1;
      analysis = to_json(analyse_reference(scene, refined->trajectory, SimulationOptions{}, a));
    }
    out.flush();
  }
  lines.rethrow();
  py::dict result;
  result["relaxed_objective"] = discovery->relaxed.solution.objective;
  result["discovery_seconds"] = discovery->seconds;
  result["stage"] = refined ? refined->stage : "discovery (" + discovery->message + ")";
  result["converged"] = refined && refined->converged;
  if (refined) {
    const auto j = to_json(scene, *refined);
    for (const char* key : {"schedule", "mode_validity_violation", "phase_resim_max_error", "refinement_seconds"})
      result[key] = py::module_::import("json").attr("loads")(j[key].dump());
    result["objective"] = refined->objective;
    result["event_times"] = refined->event_times;
    result["refinement_json"] = j.dump();
  }
  if (refined && refined->converged) {
    result["reference"] = refined_reference(scene, SimulationOptions{}, refined->element_times,
                                            "plank-box flat landing (refined)", refined->trajectory);
  }
  if (analysis) result["analysis"] = py::module_::import("json").attr("loads")(analysis->dump());
  return result;
}

/// The hopper's chain (scenes::run_hopper_chain) on `task`: its report as `hopper --json` prints it
/// (to_json(HopperChain)) as a dict, with the task, the event times and the refined reference.
py::dict hopper_chain(scenes::HopperTask task, py::object progress, const std::string& initialisation, int runs,
                      int deviation_times) {
  SALTUS_REQUIRE(initialisation == "paper" || initialisation == "hop_guess",
                 "initialisation must be 'paper' or 'hop_guess', got '", initialisation, "'");
  SALTUS_REQUIRE(runs >= 1, "runs must be >= 1, got ", runs);
  SALTUS_REQUIRE(deviation_times >= 0, "deviation_times must be >= 0, got ", deviation_times);
  scenes::HopperChainOptions options = scenes::hopper_chain_options(task);
  options.initialisation =
      initialisation == "hop_guess" ? scenes::HopperInitialisation::HopGuess : scenes::HopperInitialisation::Paper;
  options.runs = runs;
  options.deviation_times = deviation_times;
  PythonLines lines(progress_sink(std::move(progress)));
  std::ostream out(&lines);
  options.progress = &out;
  std::optional<scenes::HopperChain> chain;
  {
    py::gil_scoped_release release;
    chain.emplace(scenes::run_hopper_chain(options));
    out.flush();
  }
  lines.rethrow();
  py::dict result = py::module_::import("json").attr("loads")(to_json(*chain).dump()).cast<py::dict>();
  result["task"] = task == scenes::HopperTask::OneHole ? "one hole" : "three holes";
  if (chain->refined) result["event_times"] = chain->refined->event_times;
  if (chain->refined && chain->refined->converged) {
    result["reference"] = refined_reference(  // simulated with the analysis' options
        scenes::Hopper{}, scenes::hopper_monte_carlo_simulation(), chain->refined->element_times,
        std::string("hopper over ") + (task == scenes::HopperTask::OneHole ? "one hole" : "three holes") + " (refined)",
        std::move(chain->refined->trajectory));
  }
  return result;
}

}  // namespace

void bind_optimal_control(py::module_& m) {
  py::module_ oc = m.def_submodule("optimal_control",
                                   "Optimal references by time-freezing and the mode-schedule refinement (the OCPs "
                                   "the scene library compiles).");
  oc.def("point_mass_to_the_target", &point_mass_to_the_target, py::arg("progress") = py::none(),
         "The point mass with friction (mu = 0.2) from rest at (0, 1) m to rest on the table at x = 3 m at T = 2 s, "
         "minimising the integral of u'u (|u_i| <= 20 N): discovery by the time-freezing homotopy (FESD, Ipopt), "
         "then the mode-schedule refinement. `progress`: a callable given each progress line (str), or None for the "
         "logger 'saltus' (INFO). Returns a dict: stage ('refined' when every check passed), converged, objective, "
         "relaxed_objective, schedule, event_times [s], mode_validity_violation, phase_resim_max_error, "
         "discovery_seconds, refinement_seconds, ipopt_iterations, homotopy_steps, complementarity, refinement_json "
         "(the C++ report), and reference: the refined reference as a PointMassTrajectory (its optimal input law "
         "inside; breakpoints at its elements) for jump_gains, linearise and tracking.");
  oc.def("plank_box_flat_landing", &plank_box_flat_landing, py::arg("progress") = py::none(),
         py::arg("max_edits") = 0, py::arg("runs") = 100,
         "The plank-box flat landing (T = 1.5 s: the box lands flat on the compliant plank with both bottom corners "
         "at once, slides, lifts off to its target), optimised and analysed as `plank_box --json` does it: discovery "
         "by the time-freezing homotopy, the mode-schedule refinement with up to `max_edits` (>= 0) schedule edits "
         "(default 0: only the one-edit check; the lift-off edit that the C++ example tries costs about two minutes "
         "and does not solve), then the library's analysis (jump gains, LQR tracking design, stability check, "
         "`runs` (>= 1) closed-loop Monte Carlo runs on one thread). About 2 minutes on one core. `progress`: as "
         "point_mass_to_the_target. Returns a dict: stage, converged, objective, relaxed_objective, schedule, "
         "event_times [s], mode_validity_violation, phase_resim_max_error, discovery_seconds, refinement_seconds, "
         "refinement_json, and when refined: reference (a PlankBoxTrajectory) and analysis (the analysis report as a "
         "dict: events with their jump gains, design, verdict, bounds, monte_carlo). Raises InvalidArgument for "
         "max_edits < 0, runs < 1 or a progress that is not callable.");
  const char* hopper_keys =
      "Returns a dict, the report of `hopper --json`: converged, initialisation, stage ('refined' when every check "
      "passed, 'converged, checks failed: ...', 'not converged', 'discovery (<why>)' or 'refinement (<why>)'), "
      "relaxed_objective, discovery_seconds, discovery (the homotopy's steps), footholds [m]; when the refinement "
      "ran (any stage but 'discovery (...)' and 'refinement (...)'): objective (the integral of "
      "u'u, N^2 m^2 s), schedule, schedule_edits, mode_validity_violation, max_path_violation, target_error, "
      "phase_resim_max_error (the per-phase re-simulation's distance, state units), events and event_times [s], "
      "refinement_seconds, solve_seconds, refinement (the C++ report); when it converged: analysis (the analysis "
      "report as a dict: events with their saltation norms, design, verdict, upper_bound, lower_bound, "
      "predicted_rate [1/s], runs and kept_event_sequence (also in monte_carlo), monte_carlo, agree, seconds) and "
      "reference (the refined reference as a "
      "HopperTrajectory, q = (x, z, phi_hip, phi_knee) [m, rad], u = hip and knee torques [N m]); and task. "
      "`progress`: as point_mass_to_the_target. Raises InvalidArgument for runs < 1, deviation_times < 0 or a "
      "progress that is not callable";
  oc.def(
      "hopper_over_three_holes",
      [](py::object progress, const std::string& initialisation, int runs, int deviation_times) {
        return hopper_chain(scenes::HopperTask::ThreeHoles, std::move(progress), initialisation, runs, deviation_times);
      },
      py::arg("progress") = py::none(), py::arg("initialisation") = "paper", py::arg("runs") = 200,
      py::arg("deviation_times") = 60,
      (std::string("The flagship OCP of the time-freezing paper (Section 6): the one-legged hopper from rest at x = 0 "
                   "to x = 3 m in T = 2.5 s over three holes, minimising the integral of u'u (|u_i| <= 60 N m), "
                   "optimised and analysed as `hopper --json` does it (the same C++ function, "
                   "scenes::run_hopper_chain): discovery by the time-freezing homotopy after the continuation on "
                   "the holes (initialisation 'paper': the start state at every node, zero torques) or from the "
                   "kinematic guess of three hops ('hop_guess'), the footsteps of its schedule, their mode-schedule "
                   "refinement (Radau IIA n_s = 4, mesh refined to local error 2e-8), then the library's analysis "
                   "(jump gains, LQR design R = I, stability check, `runs` (>= 1) closed-loop Monte Carlo runs at "
                   "eps = 1e-6 on one thread, each recording its deviation at `deviation_times` (>= 0) times). "
                   "About 3 minutes on one core of an otherwise idle machine, about 5 beside other work. ") +
       hopper_keys + ", or an initialisation other than 'paper' and 'hop_guess'.")
          .c_str());
  oc.def(
      "hopper_over_one_hole",
      [](py::object progress, int runs, int deviation_times) {
        return hopper_chain(scenes::HopperTask::OneHole, std::move(progress), "paper", runs, deviation_times);
      },
      py::arg("progress") = py::none(), py::arg("runs") = 30, py::arg("deviation_times") = 0,
      (std::string("The hopper's one-hole bed (HopperOverOneHole: from rest at x = 0 to (1, 0.4, 0, 0) in T = 1 s "
                   "over the first hole, N = 8 control intervals): the chain of hopper_over_three_holes (the same "
                   "C++ function) from the paper's initialisation, the refinement's mesh to local error 2e-7, "
                   "`runs` Monte Carlo runs (default 30), no deviation times by default. About a minute on one "
                   "core. ") +
       hopper_keys + ".")
          .c_str());
}

}  // namespace saltus::python
