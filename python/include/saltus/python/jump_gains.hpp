// Binding a scene's jump gains for Python: jump_gains(trajectory) -> one JumpGain per event (the
// class JumpGain is saltus._saltus's).
#pragma once

#include <saltus/python/trajectory.hpp>
#include <saltus/sensitivity/jump_gain.hpp>

namespace saltus::python {


/// One event's gain as Python sees it (scene-independent: dynamic sizes).
struct PyJumpGain {
  double t = 0.0;                   ///< s, the event time
  Eigen::MatrixXd G_z, G_v;         ///< (nx, nx), (nx, nu)
  Eigen::RowVectorXd dt_dz, dt_dv;  ///< (nx,), (nu,): first-order shift of the event time, s per unit deviation
  Eigen::VectorXd f_minus, f_plus;  ///< (nx,): the flows before and after
  double jump_map_residual = 0.0;
  int transitions = 0;
};

inline FeedbackTreatment feedback_from(const std::string& s) {
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


/// Binds the overload jump_gains(trajectory: <scene>Trajectory, ...) in m.
template <Scene S>
void bind_jump_gains_of(py::module_& m, const char* doc = "") {
  m.def("jump_gains", &gains_of<S>, py::arg("trajectory"), py::arg("feedback") = "closed_loop",
        py::arg("grazing_threshold") = 1e-8, doc);
}

}  // namespace saltus::python
