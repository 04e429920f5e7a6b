// The module's simulation unit: the classes Segment and Event, simulate() and the trajectory
// classes of the scene library's scenes (saltus/python/trajectory.hpp), and the scene library's
// canonical reference motions (saltus.references: C++ input laws). The hopper and the spatial box
// are bound like the others: simulate, their trajectories, polish.
#include "common.hpp"
#include "scenes/references.hpp"

namespace saltus::python {

namespace {

template <Scene S>
std::shared_ptr<PyTrajectory<S>> from_reference(references::Reference<S>&& r) {
  auto out = std::make_shared<PyTrajectory<S>>();
  out->scene = std::make_shared<const S>(r.scene);
  out->options = r.options;
  out->name = r.name;
  out->trajectory = std::move(r.trajectory);
  return out;
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<PySegment>(m, "Segment", "A smooth segment of a trajectory: one contact mode on [t_begin, t_end] [s].")
      .def_readonly("mode", &PySegment::mode, "the mode as the library writes it, e.g. 'C_L:slip+ C_R:stick'")
      .def_readonly("contact_modes", &PySegment::contact_modes, "per contact: 'open', 'stick' or 'slip'")
      .def_readonly("t_begin", &PySegment::t_begin)
      .def_readonly("t_end", &PySegment::t_end)
      .def_readonly("times", &PySegment::times, "(n,) s: the integrator's step points, t_begin first, t_end last")
      .def_readonly("states", &PySegment::states, "(n, nx): x = (q, v) at `times`")
      .def_readonly("sliding_contact", &PySegment::sliding_contact,
                    "the contact that slides on its surface through the segment under the equivalent control of a "
                    "mode-switching input law (Filippov sliding), -1 when none")
      .def("__repr__", [](const PySegment& s) {
        return detail::concat("Segment(", s.mode, " on [", s.t_begin, ", ", s.t_end, "] s, ", s.times.size(),
                              " points)");
      });
  py::class_<PyEvent>(m, "Event", "An event: the guards that fired at t [s], the state and mode before and after.")
      .def_readonly("t", &PyEvent::t)
      .def_readonly("impact", &PyEvent::impact, "an impulse was applied (v jumps)")
      .def_readonly("input_jump", &PyEvent::input_jump,
                    "a jump of the input at a breakpoint fired the event (a release or slip onset whose time is "
                    "fixed, not a crossing: its jump gain is linear with dt = 0)")
      .def_readonly("guards", &PyEvent::guards,
                    "list of (contact index, contact name, kind): kind 'touchdown', 'release', 'stop' or 'slip-onset'")
      .def_readonly("mode_before", &PyEvent::mode_before)
      .def_readonly("mode_after", &PyEvent::mode_after)
      .def_readonly("contact_modes_before", &PyEvent::contact_modes_before)
      .def_readonly("contact_modes_after", &PyEvent::contact_modes_after)
      .def_readonly("x_minus", &PyEvent::x_minus, "(nx,) the state just before")
      .def_readonly("x_plus", &PyEvent::x_plus, "(nx,) the state just after")
      .def("__repr__", [](const PyEvent& e) {
        return detail::concat("Event(t=", e.t, ", ", e.mode_before, " -> ", e.mode_after, ")");
      });

  // One docstring for the overload set (pybind11 lists every overload's signature above it).
  bind_trajectory<scenes::BouncingBall>(
      m, "BouncingBall",
      "Event-driven simulation of `scene` from x0 (nx = 2 nq: q then v; scene units: m, rad, m/s, rad/s) at t0 to "
      "t_final [s]. `input`: None (u = 0), a constant u of size nu [N, N m], or a Python callable u(t, x) -> array "
      "of size nu. Returns the scene's Trajectory. Raises saltus.InvalidArgument (wrong size, NaN, t_final <= t0, a "
      "state below a contact), saltus.NumericalFailure, saltus.ContactProblemFailure, saltus.NonSpdMassMatrix.");
  bind_trajectory<scenes::PointMass>(m, "PointMass");
  bind_trajectory<scenes::PlankBox>(m, "PlankBox");
  bind_trajectory<scenes::Hopper>(m, "Hopper");
  bind_trajectory<scenes::SpatialBox>(m, "SpatialBox");

  py::module_ refs = m.def_submodule("references", "The scene library's canonical reference motions (C++ input laws).");
  refs.def(
      "example3", [](double t_final) { return from_reference(references::example3(t_final)); },
      py::arg("t_final") = 2.0,
      "PointMass, time-freezing paper Example 3: u = (7, 0) N for t < 1 s, (7, 2 g (t - 1)) after, from height 1 m at "
      "rest: impact at sqrt(2/g) s into frictionless contact, sliding, lift-off (release) at t = 1.5 s.");
  refs.def(
      "point_mass_with_friction", [] { return from_reference(references::point_mass_with_friction()); },
      "PointMass with planar Coulomb friction (mu = 0.5) under u = (t^2, 2 t^2) N: impact into slip, slip->stick, "
      "stick->slip, release.");
  refs.def(
      "point_mass_hop", [](double t_final) { return from_reference(references::point_mass_hop(t_final)); },
      py::arg("t_final") = 2.0, "PointMass, a periodic hop of period 1 s (release, flight, touchdown).");
  refs.def(
      "hopper", [] { return from_reference(references::hopper()); },
      "Hopper dropped from 5 cm (foot height) with the legs bent (phi_hip 0.4, phi_knee -0.8 rad) at 2 m/s forwards "
      "under the open-loop torques (0, -10 t) N m: touchdown into slip, lift-off 5 ms later, touchdown into slip, "
      "slip->stick.");
  refs.def(
      "hopper_push_off", [] { return from_reference(references::hopper_push_off()); },
      "Hopper under a joint-space PD law (a feedback law): dropped from 5 cm crouched (hip 0.4, knee -0.8 rad; kp 40, "
      "kd 2) at 0.3 m/s forwards it lands into stick; around t = 0.3 s the targets and gains blend (tanh, 10 ms) to a "
      "stiff push (hip 0.15, knee -0.3; kp 150, kd 3): stick->slip, then lift-off (release).");
  refs.def(
      "plank_box", [] { return from_reference(references::plank_box()); },
      "PlankBox: the tilted box's right corner lands and slips, then its left corner lands and both stick.");
}

}  // namespace saltus::python
