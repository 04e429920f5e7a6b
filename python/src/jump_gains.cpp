// Jump gains (saltation matrices) of a trajectory's events, z+ = G_z z- + G_v v- (thesis
// C.37-C.38; sensitivity/jump_gain.hpp): one gain per event, as NumPy arrays.
#include "common.hpp"

#include <saltus/sensitivity/jump_gain.hpp>

namespace saltus::python {

namespace {

/// One event's gain as Python sees it (scene-independent: dynamic sizes).
struct PyJumpGain {
  double t = 0.0;                   ///< s, the event time
  Eigen::MatrixXd G_z, G_v;         ///< (nx, nx), (nx, nu)
  Eigen::RowVectorXd dt_dz, dt_dv;  ///< (nx,), (nu,): first-order shift of the event time, s per unit deviation
  Eigen::VectorXd f_minus, f_plus;  ///< (nx,): the flows before and after
  double jump_map_residual = 0.0;
  int transitions = 0;
};

FeedbackTreatment feedback_from(const std::string& s) {
  if (s == "closed_loop") return FeedbackTreatment::ClosedLoop;
  if (s == "signal") return FeedbackTreatment::Signal;
  throw InvalidArgument(detail::concat("feedback must be 'closed_loop' or 'signal', got '", s, "'"));
}

template <Scene S>
std::vector<PyJumpGain> gains_of(const PyTrajectory<S>& t, const std::string& feedback, double grazing_threshold) {
  JumpGainOptions options;
  options.feedback = feedback_from(feedback);
  options.grazing_threshold = grazing_threshold;
  std::vector<JumpGain<S>> gains;
  {
    py::gil_scoped_release release;  // a Python input law takes the GIL back per call
    gains = jump_gains(*t.scene, t.trajectory, options);
  }
  std::vector<PyJumpGain> out;
  for (std::size_t i = 0; i < gains.size(); ++i) {
    const JumpGain<S>& g = gains[i];
    out.push_back({t.trajectory.events[i].t, g.G_z, g.G_v, g.dt_dz, g.dt_dv, g.f_minus, g.f_plus, g.jump_map_residual,
                   g.transitions});
  }
  return out;
}

}  // namespace

void bind_jump_gains(py::module_& m) {
  py::class_<PyJumpGain>(m, "JumpGain",
                         "The first-order jump gain of one event: z+ = G_z z- + G_v v-, z the state deviation from "
                         "the (extended) reference at the nominal event time, v the input deviation; the event time "
                         "moves by dt = dt_dz z- + dt_dv v- [s].")
      .def_readonly("t", &PyJumpGain::t, "s: the nominal event time")
      .def_readonly("G_z", &PyJumpGain::G_z, "(nx, nx): the saltation matrix (C.37)")
      .def_readonly("G_v", &PyJumpGain::G_v, "(nx, nu): the input gain (C.38), nonzero at state-input guards")
      .def_readonly("dt_dz", &PyJumpGain::dt_dz, "(nx,) s per unit state deviation")
      .def_readonly("dt_dv", &PyJumpGain::dt_dv, "(nu,) s per unit input deviation")
      .def_readonly("f_minus", &PyJumpGain::f_minus, "(nx,): the flow x' before the event")
      .def_readonly("f_plus", &PyJumpGain::f_plus, "(nx,): the flow x' after the event")
      .def_readonly("jump_map_residual", &PyJumpGain::jump_map_residual,
                    "max |g(x-) - x+|: the differentiated jump map against the impact solver")
      .def_readonly("transitions", &PyJumpGain::transitions, "transitions composed at this instant (a chain: > 1)")
      .def("__repr__",
           [](const PyJumpGain& g) { return detail::concat("JumpGain(t=", g.t, ", nx=", g.G_z.rows(), ")"); });

  const char* doc =
      "The jump gain of every event of `trajectory`, in order, under its own input law. feedback: 'closed_loop' (a "
      "state-dependent input law acts on the perturbed state) or 'signal' (the input is the reference's signal); "
      "grazing_threshold: relative |gamma_dot| below which the crossing is grazing. Raises saltus.GrazingEvent, "
      "saltus.SimultaneousActivation (simultaneous guards that a perturbation separates: conewise gain), "
      "saltus.ContactProblemFailure.";
  m.def("jump_gains", &gains_of<scenes::BouncingBall>, py::arg("trajectory"), py::arg("feedback") = "closed_loop",
        py::arg("grazing_threshold") = 1e-8, doc);
  m.def("jump_gains", &gains_of<scenes::PointMass>, py::arg("trajectory"), py::arg("feedback") = "closed_loop",
        py::arg("grazing_threshold") = 1e-8);
  m.def("jump_gains", &gains_of<scenes::PlankBox>, py::arg("trajectory"), py::arg("feedback") = "closed_loop",
        py::arg("grazing_threshold") = 1e-8);
}

}  // namespace saltus::python
