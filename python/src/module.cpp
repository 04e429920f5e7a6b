// The compiled module saltus._saltus; the package saltus (python/saltus/__init__.py) re-exports it.
// One binding unit per concept: errors.cpp, scenes.cpp (scenes and simulation options),
// simulation.cpp (simulate, trajectories, the library's references), jump_gains.cpp,
// tracking.cpp (tracking designs, stability check, Monte Carlo), optimal_control.cpp (the
// optimise-then-analyse pipeline).
#include "common.hpp"

PYBIND11_MODULE(_saltus, m) {
  m.doc() = "Saltus: hybrid mechanical systems with impacts and friction (C++ bindings; see the package saltus).";
  m.attr("__version__") = SALTUS_VERSION_STRING;
  using namespace saltus::python;
  bind_errors(m);  // first: the exception translator applies to everything bound after it
  bind_scenes(m);
  bind_simulation(m);
  bind_jump_gains(m);
  bind_tracking(m);
  bind_optimal_control(m);
}
