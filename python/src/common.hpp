// What the binding units of the module _saltus share: the scene library and the templated
// bindings of one scene (saltus/python/*.hpp, also what a user's own extension module includes),
// and the entry point of each unit.
//
// The scenes' machinery (Simulator, JumpGainSolver, LinearisedSystem, the tracking design and its
// checks) is compiled once in the scene library saltus_scenes and declared `extern` by the scene
// headers (SALTUS_DECLARE_SCENE, SALTUS_DECLARE_SCENE_SENSITIVITY): this module includes
// declarations only and links it, so a binding unit compiles in seconds.
#pragma once

#include "scenes/all_scenes.hpp"

#include <saltus/python/jump_gains.hpp>
#include <saltus/python/tracking.hpp>
#include <saltus/python/trajectory.hpp>

namespace saltus::python {

void bind_errors(py::module_& m);
void bind_scenes(py::module_& m);
void bind_simulation(py::module_& m);
void bind_jump_gains(py::module_& m);
void bind_tracking(py::module_& m);
void bind_optimal_control(py::module_& m);

}  // namespace saltus::python
