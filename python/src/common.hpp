// What the binding units of the module _saltus share: the trajectory as Python holds it (with its
// own copy of the scene and the options it was simulated with), the conversion of NumPy input to
// a scene's fixed-size state with the library's own error type, and the entry point of each unit.
//
// The scenes' machinery (Simulator, JumpGainSolver, LinearisedSystem, the tracking design and its
// checks) is compiled once in the scene library saltus_scenes and declared `extern` by the scene
// headers (SALTUS_DECLARE_SCENE, SALTUS_DECLARE_SCENE_SENSITIVITY): this module includes
// declarations only and links it, so a binding unit compiles in seconds.
#pragma once

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/simulation/simulator.hpp>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

namespace saltus::python {

namespace py = pybind11;

/// Arrays returned to Python: C-contiguous (rows are samples).
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A simulated (or library-made) trajectory with what it needs to be read later: its scene (a
/// copy: the Python scene object may go away), the options it was simulated with (a
/// linearisation re-simulates micro-events with them) and the initial state.
template <Scene S>
struct PyTrajectory {
  std::shared_ptr<const S> scene;
  SimulationOptions options;
  HybridTrajectory<S> trajectory;
  std::string name;  ///< for repr: the reference's name, or "simulation"
};

/// x as the scene's fixed-size state; @throws InvalidArgument naming `what` on a wrong size (the
/// library's own checks of finiteness follow where it uses the state).
template <Scene S>
Vec<2 * S::nq> to_state(const Eigen::VectorXd& x, const char* what) {
  constexpr int nx = 2 * S::nq;
  SALTUS_REQUIRE(x.size() == nx, what, " has size ", x.size(), ", expected nx = 2 nq = ", nx, " for the scene ",
                 S::name);
  return x;
}

/// A square matrix argument of size n (None: the given default). @throws InvalidArgument.
template <int N>
Mat<N, N> to_square(const std::optional<Eigen::MatrixXd>& m, const Mat<N, N>& fallback, const char* what) {
  if (!m) return fallback;
  SALTUS_REQUIRE(m->rows() == N && m->cols() == N, what, " has shape (", m->rows(), ", ", m->cols(), "), expected (",
                 N, ", ", N, ")");
  return *m;
}

/// The Python class name of a scene-templated binding: the scene's name in CamelCase + suffix
/// ("bouncing_ball", "Trajectory" -> "BouncingBallTrajectory").
template <Scene S>
std::string class_name(const char* suffix) {
  std::string out;
  bool upper = true;
  for (const char* c = S::name; *c; ++c) {
    if (*c == '_') {
      upper = true;
      continue;
    }
    out += upper ? static_cast<char>(*c - 'a' + 'A') : *c;
    upper = false;
  }
  return out + suffix;
}

void bind_errors(py::module_& m);
void bind_scenes(py::module_& m);
void bind_simulation(py::module_& m);
void bind_jump_gains(py::module_& m);
void bind_tracking(py::module_& m);

}  // namespace saltus::python
