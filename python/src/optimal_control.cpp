// The optimise-then-analyse pipeline from Python, on the OCP the scene library compiles
// (scenes/time_freezing_examples.hpp, PointMassToTheTarget: the point mass with friction from rest
// at (0, 1) m to rest on the table at x = 3 m at T = 2 s, minimising the integral of u'u): the
// time-freezing homotopy discovers the contact schedule, the mode-schedule refinement makes the
// reference exact, and the refined reference comes back as a PointMassTrajectory that jump_gains,
// linearise and tracking analyse. The solver's progress lines reach Python: a callable gets each
// line, or else the logging module's logger "saltus" (level INFO).
#include "common.hpp"
#include "scenes/time_freezing_examples.hpp"

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

py::dict point_mass_to_the_target(py::object progress) {
  using namespace timefreezing;
  using Case = scenes::PointMassToTheTarget;
  if (progress.is_none()) progress = py::module_::import("logging").attr("getLogger")("saltus").attr("info");
  SALTUS_REQUIRE(PyCallable_Check(progress.ptr()), "progress must be a callable taking one line (str) or None");
  PythonLines lines(progress);
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
}

}  // namespace saltus::python
