// Jump gains (saltation matrices) of a trajectory's events, z+ = G_z z- + G_v v- (thesis
// C.37-C.38; sensitivity/jump_gain.hpp): one gain per event, as NumPy arrays.
#include "common.hpp"

#include <saltus/sensitivity/jump_gain.hpp>

namespace saltus::python {

void bind_jump_gains(py::module_& m) {
  py::class_<PyConewisePiece>(m, "ConewisePiece",
                              "One piece of a conewise gain: the activation order of the event's guards, its gain "
                              "z+ = G_z z- + G_v v on the cone cone_z z- + cone_v v >= 0 (row-wise).")
      .def_readonly("order", &PyConewisePiece::order,
                    "the micro-events in order, each a list of (contact index, contact name, kind)")
      .def_readonly("G_z", &PyConewisePiece::G_z, "(nx, nx)")
      .def_readonly("G_v", &PyConewisePiece::G_v, "(nx, nu)")
      .def_readonly("cone_z", &PyConewisePiece::cone_z, "(rows, nx)")
      .def_readonly("cone_v", &PyConewisePiece::cone_v, "(rows, nu)")
      .def_readonly("x_plus", &PyConewisePiece::x_plus, "(nx,): the post-event state of this order")
      .def_readonly("mode_after", &PyConewisePiece::mode_after)
      .def_readonly("nominal_outcome", &PyConewisePiece::nominal_outcome,
                    "x_plus and mode_after are the nominal event's: z+ is a deviation from the nominal reference")
      .def("__repr__", [](const PyConewisePiece& p) {
        std::string order;
        for (const auto& g : p.order) {
          if (!order.empty()) order += " then ";
          for (std::size_t k = 0; k < g.size(); ++k)
            order += (k ? "+" : "") + g[k][1].cast<std::string>() + " " + g[k][2].cast<std::string>();
        }
        return "ConewisePiece(" + order + " -> " + p.mode_after + ")";
      });

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
  const char* conewise_doc =
      "The conewise gain of the simultaneous event `event` (an index into trajectory.events) under the "
      "trajectory's own input law and simulation options: pieces built on demand (build_all() builds all). Raises "
      "saltus.InvalidArgument (an event without guards, an index out of range), saltus.GrazingEvent.";
  bind_jump_gains_of<scenes::BouncingBall>(m, "BouncingBall", doc, conewise_doc);
  bind_jump_gains_of<scenes::PointMass>(m, "PointMass");
  bind_jump_gains_of<scenes::PlankBox>(m, "PlankBox");
  bind_jump_gains_of<scenes::Hopper>(m, "Hopper");
  bind_jump_gains_of<scenes::SpatialBox>(m, "SpatialBox");
}

}  // namespace saltus::python
