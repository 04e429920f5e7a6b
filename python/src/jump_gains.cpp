// Jump gains (saltation matrices) of a trajectory's events, z+ = G_z z- + G_v v- (thesis
// C.37-C.38; sensitivity/jump_gain.hpp): one gain per event, as NumPy arrays.
#include "common.hpp"

#include <saltus/sensitivity/jump_gain.hpp>

namespace saltus::python {

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
  bind_jump_gains_of<scenes::BouncingBall>(m, doc);
  bind_jump_gains_of<scenes::PointMass>(m);
  bind_jump_gains_of<scenes::PlankBox>(m);
}

}  // namespace saltus::python
