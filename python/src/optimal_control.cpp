// The optimise-then-analyse pipeline from Python, on the OCP the scene library compiles
// (scenes/time_freezing_examples.hpp, PointMassToTheTarget: the point mass with friction from rest
// at (0, 1) m to rest on the table at x = 3 m at T = 2 s, minimising the integral of u'u): the
// time-freezing homotopy discovers the contact schedule, the mode-schedule refinement makes the
// reference exact, and the refined reference comes back as a PointMassTrajectory that jump_gains,
// linearise and tracking analyse. The solver's progress lines reach Python: a callable gets each
// line, or else the logging module's logger "saltus" (level INFO).
#include "common.hpp"
#include "scenes/plank_box_landing.hpp"
#include "scenes/plank_box_tracking.hpp"
#include "scenes/time_freezing_examples.hpp"

#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/refinement/discovery.hpp>

#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/refinement_io.hpp>

#include <optional>
#include <ostream>
#include <streambuf>

namespace saltus::python {

namespace {

/// A stream buffer that hands every complete line to a Python callable (under the GIL). An
/// exception the callable raises is kept and raised by rethrow() after the solve (an ostream would
/// swallow it).
class PythonLines : public std::streambuf {
 public:
  explicit PythonLines(py::object sink) : sink_(std::move(sink)) {}
  ~PythonLines() override {
    py::gil_scoped_acquire gil;
    sink_ = py::object();
  }
  void rethrow() {
    flush_line();
    if (error_) throw *error_;
  }

 protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    if (traits_type::to_char_type(c) == '\n')
      flush_line();
    else
      line_ += traits_type::to_char_type(c);
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    for (std::streamsize k = 0; k < n; ++k) overflow(traits_type::to_int_type(s[k]));
    return n;
  }

 private:
  void flush_line() {
    if (line_.empty()) return;
    py::gil_scoped_acquire gil;
    if (!error_) {
      try {
        sink_(line_);
      } catch (py::error_already_set& e) {
        error_ = std::move(e);
      }
    }
    line_.clear();
  }
  py::object sink_;
  std::string line_;
  std::optional<py::error_already_set> error_;
};

/// The progress callable: `progress`, or the logger "saltus" at INFO when None.
py::object progress_sink(py::object progress) {
  if (progress.is_none()) progress = py::module_::import("logging").attr("getLogger")("saltus").attr("info");
  SALTUS_REQUIRE(PyCallable_Check(progress.ptr()), "progress must be a callable taking one line (str) or None");
  return progress;
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
    auto reference = std::make_shared<PyTrajectory<scenes::PointMass>>();
    reference->scene = std::make_shared<const scenes::PointMass>(mass);
    reference->options = precise_simulation();
    reference->options.breakpoints = refined->element_times;  // the optimal input is piecewise constant
    reference->name = "point mass to the target (refined)";
    reference->trajectory = refined->trajectory;
    result["reference"] = reference;
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
    auto reference = std::make_shared<PyTrajectory<scenes::PlankBox>>();
    reference->scene = std::make_shared<const scenes::PlankBox>(scene);
    reference->options = SimulationOptions{};
    reference->options.breakpoints = refined->element_times;  // the optimal input is piecewise constant
    reference->name = "plank-box flat landing (refined)";
    reference->trajectory = refined->trajectory;
    result["reference"] = reference;
  }
  if (analysis) result["analysis"] = py::module_::import("json").attr("loads")(analysis->dump());
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
}

}  // namespace saltus::python
