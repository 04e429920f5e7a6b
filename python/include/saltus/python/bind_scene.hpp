// A user's own scene in Python, in an extension module of the user's own: one macro binds the
// scene (default-constructed), simulate(), its trajectory (with trajectory_from_json()), jump_gains(),
// conewise_gain(), the tracking designs with their stability check and Monte Carlo batch, and
// analyse_reference(), exactly as saltus binds the scene library's:
//
//   // my_scene_python.cpp
//   #include "my_scene.hpp"                       // the scene, with SALTUS_DECLARE_SCENE and
//                                                 // SALTUS_DECLARE_SCENE_SENSITIVITY (or instantiate
//                                                 // them here: SALTUS_INSTANTIATE_SCENE, ...)
//   #include <saltus/python/bind_scene.hpp>
//   PYBIND11_MODULE(my_scene_python, m) { SALTUS_PYTHON_BIND_SCENE(m, MyScene, "MyScene"); }
//
//   # CMake: pybind11_add_module(my_scene_python my_scene_python.cpp my_scene.cpp)
//   #        target_link_libraries(my_scene_python PRIVATE saltus::hybrid saltus::sensitivity)
//   #        target_include_directories(my_scene_python PRIVATE <saltus>/python/include)
//
//   >>> import saltus, my_scene_python as my
//   >>> traj = my.simulate(my.MyScene(), x0, 0.0, 1.0)   # a MySceneTrajectory
//   >>> saltus.jump_gains(traj)                           # the overloads live in my_scene_python:
//   >>> my.jump_gains(traj)                               #   call them there
//
// The classes every scene shares (Segment, Event, JumpGain, SimulationOptions, the reports) and
// the exception translation (saltus.InvalidArgument, ...) are saltus._saltus's: the macro imports
// saltus first, and the extension must be built with the same pybind11 as saltus (pybind11 shares
// registered types between modules of one build). The scene needs a default constructor; a scene
// with parameters binds its own class and calls bind_scene_functions<S>(m, "MyScene").
#pragma once

#include <saltus/python/jump_gains.hpp>
#include <saltus/python/tracking.hpp>
#include <saltus/python/trajectory.hpp>

namespace saltus::python {

/// simulate, <name>Trajectory, jump_gains, and the tracking bindings of S (tracking.hpp) in m.
template <Scene S>
void bind_scene_functions(py::module_& m, const std::string& name) {
  py::module_::import("saltus");  // the shared classes and the exception translator
  bind_trajectory<S>(m, name,
                     "Event-driven simulation of the scene from x0 (nx = 2 nq) at t0 to t_final [s] under `input` "
                     "(None, a constant u (nu,), or a Python callable u(t, x)); see saltus.simulate.");
  bind_jump_gains_of<S>(m, name, "The jump gain of every event of `trajectory`; see saltus.jump_gains.",
                        "The conewise gain of a simultaneous event; see saltus.conewise_gain.");
  bind_scene_tracking<S>(m, name, "The whole analysis of a reference in one call; see saltus.analyse_reference.");
}

/// The scene class `name` (default constructor, nq, nx, nu, nc, the contacts' names) and
/// bind_scene_functions<S>.
template <Scene S>
void bind_scene(py::module_& m, const std::string& name) {
  py::module_::import("saltus");
  py::class_<S>(m, name.c_str())
      .def(py::init<>())
      .def_property_readonly_static("nq", [](py::object) { return S::nq; }, "configuration size nq")
      .def_property_readonly_static("nx", [](py::object) { return 2 * S::nq; }, "state size nx = 2 nq: x = (q, v)")
      .def_property_readonly_static("nu", [](py::object) { return S::nu; }, "input size nu")
      .def_property_readonly_static("nc", [](py::object) { return S::nc; }, "number of contacts nc")
      .def_property_readonly("contacts", [](const S& s) {
        std::vector<std::string> names;
        for (int i = 0; i < S::nc; ++i) names.push_back(s.contact(i).name);
        return names;
      });
  bind_scene_functions<S>(m, name);
}

}  // namespace saltus::python

/// In PYBIND11_MODULE(name, m) { ... }: binds scene type S (a default-constructible scene whose
/// machinery is declared or instantiated in this translation unit) as the Python class `name`.
#define SALTUS_PYTHON_BIND_SCENE(m, S, name) ::saltus::python::bind_scene<S>(m, name)
