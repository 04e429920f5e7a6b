// Binding a scene's simulation for Python: the trajectory as Python holds it (with its own copy of
// the scene and the options it was simulated with), simulate(scene, x0, t0, t_final, input,
// options) for the scene, the trajectory's segments (dense output as NumPy arrays), events, dense
// sampling, JSON and CSV, and polish(scene, csv): a reference read back from CSV, re-simulated.
// Used by the module saltus._saltus for the scene library's scenes and by a user's own extension
// module (bind_scene.hpp).
//
// The GIL is released while the simulator runs; an input law written in Python takes it back for
// each call (each right-hand side evaluation: that is the speed cost of a Python law).
#pragma once

#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace saltus::python {

namespace py = pybind11;

/// Arrays returned to Python: C-contiguous (rows are samples).
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A simulated (or library-made) trajectory with what it needs to be read later: its scene (a
/// copy: the Python scene object may go away), the options it was simulated with (a
/// linearisation re-simulates micro-events with them) and a name.
template <Scene S>
struct PyTrajectory {
  std::shared_ptr<const S> scene;
  SimulationOptions options;
  HybridTrajectory<S> trajectory;
  std::string name;  ///< for repr: the reference's name, or "simulation"
};

/// " for the scene <S::name>" in messages, where the scene has a name.
template <Scene S>
std::string scene_label() {
  if constexpr (requires { S::name; })
    return std::string(" for the scene ") + S::name;
  else
    return "";
}

/// x as the scene's fixed-size state; @throws InvalidArgument naming `what` on a wrong size (the
/// library's own checks of finiteness follow where it uses the state).
template <Scene S>
Vec<2 * S::nq> to_state(const Eigen::VectorXd& x, const char* what) {
  constexpr int nx = 2 * S::nq;
  SALTUS_REQUIRE(x.size() == nx, what, " has size ", x.size(), ", expected nx = 2 nq = ", nx, scene_label<S>());
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

/// A segment as Python sees it (scene-independent): the dense output's step points.
struct PySegment {
  std::string mode;                        ///< describe(): "ground:closed", "C_L:slip+ C_R:stick"
  std::vector<std::string> contact_modes;  ///< per contact: "open", "stick", "slip"
  double t_begin = 0.0, t_end = 0.0;
  Eigen::VectorXd times;  ///< (n,) s: the integrator's step points, t_begin first, t_end last
  RowMatrix states;       ///< (n, nx): x = (q, v) at those times
  /// The contact sliding on its surface through the segment under the equivalent control of a
  /// mode-switching input law (Segment::sliding_contact), -1 when none.
  int sliding_contact = -1;
};

/// An event as Python sees it.
struct PyEvent {
  double t = 0.0;
  bool impact = false;
  bool input_jump = false;  ///< Event::input_jump
  std::vector<py::tuple> guards;  ///< (contact index, contact name, guard kind)
  std::string mode_before, mode_after;
  std::vector<std::string> contact_modes_before, contact_modes_after;
  Eigen::VectorXd x_minus, x_plus;
};

template <int NC>
inline std::vector<std::string> contact_modes(const Mode<NC>& mode) {
  std::vector<std::string> out;
  for (const auto& c : mode.contacts) out.emplace_back(to_string(c.mode));
  return out;
}

template <Scene S>
PySegment segment_of(const PyTrajectory<S>& t, int i) {
  const HybridTrajectory<S>& traj = t.trajectory;
  const Segment<S>& s = traj.segments[i];
  PySegment out{describe(*t.scene, s.mode), contact_modes(s.mode), s.t_begin, s.t_end, {}, {}, s.sliding_contact};
  const auto& pieces = s.x.pieces();
  if (pieces.empty()) {  // record_dense_output = false: the end points only
    const auto begin = i > 0 ? traj.events[i - 1].x_plus : traj.state(i, s.t_begin);
    out.times = Eigen::Vector2d(s.t_begin, s.t_end);
    out.states.resize(2, 2 * S::nq);
    out.states.row(0) = begin.transpose();
    out.states.row(1) = traj.state(i, s.t_end).transpose();
    return out;
  }
  const auto n = static_cast<Eigen::Index>(pieces.size());
  out.times.resize(n + 1);
  out.states.resize(n + 1, 2 * S::nq);
  for (Eigen::Index k = 0; k < n; ++k) {
    out.times[k] = pieces[k].t0;
    out.states.row(k) = pieces[k].value(pieces[k].t0).transpose();
  }
  out.times[n] = pieces.back().t1;
  out.states.row(n) = pieces.back().value(pieces.back().t1).transpose();
  return out;
}

template <Scene S>
PyEvent event_of(const PyTrajectory<S>& t, int i) {
  const Event<S>& ev = t.trajectory.events[i];
  PyEvent out;
  out.t = ev.t;
  out.impact = ev.impact();
  out.input_jump = ev.input_jump;
  for (const Guard& g : ev.guards())
    out.guards.push_back(py::make_tuple(g.contact, t.scene->contact(g.contact).name, to_string(g.kind)));
  out.mode_before = describe(*t.scene, ev.mode_before);
  out.mode_after = describe(*t.scene, ev.mode_after);
  out.contact_modes_before = contact_modes(ev.mode_before);
  out.contact_modes_after = contact_modes(ev.mode_after);
  out.x_minus = ev.x_minus;
  out.x_plus = ev.x_plus;
  return out;
}

/// A Python object that C++ may copy and destroy without the GIL (std::function copies inside
/// the simulator): the reference count is the shared_ptr's, the object is released under the GIL.
inline std::shared_ptr<py::object> hold(py::object o) {
  return std::shared_ptr<py::object>(new py::object(std::move(o)), [](py::object* p) {
    py::gil_scoped_acquire gil;
    delete p;
  });
}

/// The input law of simulate(): None (u = 0), a constant u (array of size nu), or a Python
/// callable u(t, x) -> array of size nu (x: NumPy (nx,)).
template <Scene S>
InputLaw<S> input_law(const py::object& input) {
  static constexpr int nx = 2 * S::nq, nu = S::nu;  // static: the lambdas use them without capture
  if (input.is_none()) return zero_input<S>();
  if (PyCallable_Check(input.ptr())) {
    auto f = hold(input);
    return [f](double t, const VecT<double, nx>& x, const Mode<S::nc>&) -> VecT<double, nu> {
      py::gil_scoped_acquire gil;
      py::array_t<double> xa(nx);
      std::copy(x.data(), x.data() + nx, xa.mutable_data());
      const py::object value = (*f)(t, xa);
      Eigen::VectorXd u;
      try {
        u = value.template cast<Eigen::VectorXd>();
      } catch (const py::cast_error&) {
        throw InvalidArgument(detail::concat("the input law must return ", nu, " numbers (an array of size nu), got ",
                                             py::repr(value).template cast<std::string>(), " at t = ", t));
      }
      SALTUS_REQUIRE(u.size() == nu, "the input law returned ", u.size(), " values at t = ", t, ", expected nu = ", nu);
      return u;
    };
  }
  Eigen::VectorXd u;
  try {
    u = input.cast<Eigen::VectorXd>();
  } catch (const py::cast_error&) {
    throw InvalidArgument(detail::concat("input must be None, a callable u(t, x) or ", nu, " numbers, got ",
                                         py::repr(input).cast<std::string>()));
  }
  SALTUS_REQUIRE(u.size() == nu, "the constant input has size ", u.size(), ", expected nu = ", nu);
  SALTUS_REQUIRE(u.allFinite(), "the constant input is not finite");
  const VecT<double, nu> uc = u;
  return [uc](double, const VecT<double, nx>&, const Mode<S::nc>&) { return uc; };
}

template <Scene S>
std::shared_ptr<PyTrajectory<S>> simulate(const S& scene, const Eigen::VectorXd& x0, double t0, double t_final,
                                          const py::object& input, const std::optional<SimulationOptions>& options) {
  auto out = std::make_shared<PyTrajectory<S>>();
  out->scene = std::make_shared<const S>(scene);
  out->options = options.value_or(SimulationOptions{});
  out->name = "simulation";
  const Vec<2 * S::nq> x = to_state<S>(x0, "x0");
  const InputLaw<S> law = input_law<S>(input);
  py::gil_scoped_release release;
  Simulator<S> simulator(*out->scene, out->options);
  out->trajectory = simulator.run(x, t0, t_final, law);
  return out;
}

template <Scene S>
RowMatrix sample(const PyTrajectory<S>& t, const Eigen::VectorXd& times) {
  const HybridTrajectory<S>& traj = t.trajectory;
  RowMatrix out(times.size(), 2 * S::nq);
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    SALTUS_REQUIRE(times[k] >= traj.t_begin() && times[k] <= traj.t_end(), "sample time ", times[k],
                   " is outside the trajectory [", traj.t_begin(), ", ", traj.t_end(), "]");
    out.row(k) = traj.state_at(times[k]).transpose();
  }
  return out;
}

template <Scene S>
RowMatrix inputs(const PyTrajectory<S>& t, const Eigen::VectorXd& times) {
  const HybridTrajectory<S>& traj = t.trajectory;
  RowMatrix out(times.size(), S::nu);
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    SALTUS_REQUIRE(times[k] >= traj.t_begin() && times[k] <= traj.t_end(), "sample time ", times[k],
                   " is outside the trajectory [", traj.t_begin(), ", ", traj.t_end(), "]");
    const int i = traj.segment_at(times[k]);
    out.row(k) = traj.input_at(i, std::min(times[k], traj.segments[i].t_end)).transpose();
  }
  return out;
}

/// Binds the class <scene_name>Trajectory and the overload simulate(scene: S, ...) in m. The
/// classes Segment and Event (and SimulationOptions) are those of saltus._saltus.
template <Scene S>
void bind_trajectory(py::module_& m, const std::string& scene_name, const char* simulate_doc = "") {
  using T = PyTrajectory<S>;
  const std::string name = scene_name + "Trajectory";
  py::class_<T, std::shared_ptr<T>>(m, name.c_str(),
                                    "A hybrid trajectory of the scene: smooth segments separated by events (segment i "
                                    "ends at event i). States x = (q, v) have nx = 2 nq entries; times are in s.")
      .def_property_readonly("scene", [](const T& t) { return *t.scene; }, "a copy of the scene it was simulated on")
      .def_property_readonly("options", [](const T& t) { return t.options; })
      .def_property_readonly("name", [](const T& t) { return t.name; })
      .def_property_readonly("status", [](const T& t) { return std::string(to_string(t.trajectory.status)); },
                             "'completed', 'zeno' (accumulating impacts) or 'max-events'")
      .def_property_readonly("zeno_time", [](const T& t) { return t.trajectory.zeno_time; },
                             "s: the predicted accumulation time (status 'zeno', or the last accumulation the run was continued "
                             "past, see zeno_completions; NaN otherwise)")
      .def_property_readonly("zeno_time_uncertainty", [](const T& t) { return t.trajectory.zeno_time_uncertainty; },
                             "s: how far zeno_time may be from the accumulation time: the extrapolation's part "
                             "plus the integration's (zeno_time_extrapolation_uncertainty + "
                             "zeno_time_integration_uncertainty); inf: too few touchdowns, zeno_time is the "
                             "geometric estimate; NaN without an accumulation")
      .def_property_readonly(
          "zeno_time_extrapolation_uncertainty",
          [](const T& t) { return t.trajectory.zeno_time_extrapolation_uncertainty; },
          "s: the extrapolation's part of zeno_time_uncertainty (twice the change of its second order over the "
          "last period; inf with the geometric estimate)")
      .def_property_readonly(
          "zeno_time_integration_uncertainty",
          [](const T& t) { return t.trajectory.zeno_time_integration_uncertainty; },
          "s: the integration's part of zeno_time_uncertainty: the touchdown times' error from the integration "
          "(4 times the relative tolerance times the time integrated, and the event location's resolution)")
      .def_property_readonly(
          "zeno_completions",
          [](const T& t) {
            py::list out;
            for (const ZenoCompletion& z : t.trajectory.zeno_completions) {
              py::dict d;
              d["t"] = z.t;
              d["uncertainty"] = z.uncertainty;
              d["last_touchdown"] = z.last_touchdown;
              std::vector<std::string> names;
              for (int i : z.contacts) names.push_back(t.scene->contact(i).name);
              d["contact_indices"] = z.contacts;
              d["contacts"] = names;
              d["event"] = z.event;
              out.append(d);
            }
            return out;
          },
          "the accumulations the run was continued past (SimulationOptions.zeno_completion), in time order: dicts "
          "with t (s: the accumulation time the motion was continued from), uncertainty (s: how far t may be from "
          "it; inf for the geometric estimate), last_touchdown (s: the last touchdown resolved before it), "
          "contacts (the accumulating contacts' names), contact_indices, event (the index of the completion's "
          "event in events)")
      .def_property_readonly("t_begin", [](const T& t) { return t.trajectory.t_begin(); })
      .def_property_readonly("t_end", [](const T& t) { return t.trajectory.t_end(); })
      .def_property_readonly("final_state", [](const T& t) { return Eigen::VectorXd(t.trajectory.final_state()); },
                             "(nx,)")
      .def_property_readonly(
          "statistics",
          [](const T& t) {
            const auto& s = t.trajectory.statistics;
            py::dict d;
            d["steps"] = s.steps;
            d["rejected_steps"] = s.rejected_steps;
            d["rhs_evaluations"] = s.rhs_evaluations;
            d["wall_seconds"] = s.wall_seconds;
            d["ambiguous_selections"] = s.ambiguous_selections;
            d["sliding_events"] = s.sliding_events;
            d["impacts_without_collision"] = s.impacts_without_collision;
            return d;
          },
          "integrator steps, rejected steps, right-hand side evaluations, the simulation's wall time [s], "
          "mode selections with several solutions, events after which a contact slides on its surface "
          "under the equivalent control of a mode-switching input law, and impacts without collision "
          "(SimulationOptions.painleve in C++)")
      .def_property_readonly(
          "segments",
          [](const T& t) {
            std::vector<PySegment> out;
            for (int i = 0; i < t.trajectory.segment_count(); ++i) out.push_back(segment_of(t, i));
            return out;
          },
          "list of Segment (times (n,), states (n, nx), mode)")
      .def_property_readonly(
          "events",
          [](const T& t) {
            std::vector<PyEvent> out;
            for (int i = 0; i < static_cast<int>(t.trajectory.events.size()); ++i) out.push_back(event_of(t, i));
            return out;
          },
          "list of Event (t, guards, modes before and after, x_minus, x_plus)")
      .def_property_readonly("event_times",
                             [](const T& t) {
                               Eigen::VectorXd out(t.trajectory.events.size());
                               for (std::size_t i = 0; i < t.trajectory.events.size(); ++i)
                                 out[static_cast<Eigen::Index>(i)] = t.trajectory.events[i].t;
                               return out;
                             },
                             "(n_events,) s")
      .def("sample", &sample<S>, py::arg("times"),
           "x at the given times [s] from the dense output: (n,) -> (n, nx); at an event time the state after it")
      .def("inputs", &inputs<S>, py::arg("times"), "u at the given times [s]: (n,) -> (n, nu)")
      .def(
          "to_json",
          [](const T& t, bool complete) { return to_json(t.trajectory, *t.scene, TrajectoryJsonOptions{complete}).dump(); },
          py::arg("complete") = false,
          "the C++ side's JSON (saltus::to_json) as a str: status, segments, events, zeno_time, zeno_completions, "
          "statistics; complete=True adds what saltus.read_trajectory needs to rebuild the trajectory exactly (every "
          "segment's dense output, every transition, the final state; non-finite numbers as \"inf\", \"-inf\", "
          "\"nan\"). The input law is never written.")
      .def(
          "to_csv",
          [](const T& t, double dt) {
            SALTUS_REQUIRE(dt > 0 && std::isfinite(dt), "dt must be > 0, got ", dt);
            std::ostringstream os;
            write_csv(os, t.trajectory, dt, *t.scene);
            return os.str();
          },
          py::arg("dt"),
          "the C++ side's CSV (saltus::write_csv): samples every dt [s] and both sides of every event; columns t, "
          "segment, mode, q0.., v0.., u0..")
      .def("__len__", [](const T& t) { return t.trajectory.segment_count(); }, "the number of segments")
      .def("__repr__", [name](const T& t) {
        return detail::concat(name, "(", t.name, ": ", t.trajectory.segment_count(), " segments, ",
                              t.trajectory.events.size(), " events on [", t.trajectory.t_begin(), ", ",
                              t.trajectory.t_end(), "] s, status ", to_string(t.trajectory.status), ")");
      });

  m.def(
      "polish",
      [](const S& scene, const std::string& csv, const std::optional<SimulationOptions>& options) {
        std::istringstream in(csv);
        const ImportedReference<S> imported = read_reference_csv<S>(in);
        auto out = std::make_shared<T>();
        out->scene = std::make_shared<const S>(scene);
        out->options = options.value_or(SimulationOptions{});
        out->name = "polished";
        PolishResult<S> r;
        {
          py::gil_scoped_release release;
          r = polish(*out->scene, imported, out->options);
        }
        out->trajectory = std::move(r.trajectory);
        py::dict d;
        d["trajectory"] = out;
        d["state_distance"] = r.state_distance;
        d["worst_sample_time"] = r.worst_sample_time;
        d["event_time_distance"] = r.event_time_distance;
        d["imported_events"] = r.imported_events;
        d["simulated_events"] = r.simulated_events;
        return d;
      },
      py::arg("scene"), py::arg("csv"), py::arg("options") = py::none(),
      "Reads a reference in the C++ side's CSV (Trajectory.to_csv, or another optimiser's samples t, segment, mode, "
      "q.., v.., u..) and re-simulates it under its own input, interpolated linearly (polish). Returns a dict: "
      "trajectory (the re-simulation), state_distance (max over the samples of |x_imported - x_simulated|_inf), "
      "worst_sample_time [s], event_time_distance [s], imported_events, simulated_events. Raises "
      "saltus.InvalidArgument naming the line of a malformed CSV.");

  m.def(
      "trajectory_from_json",
      [](const S& scene, const std::string& text) {
        nlohmann::json j;
        try {
          j = nlohmann::json::parse(text);
        } catch (const nlohmann::json::parse_error& e) {
          throw InvalidArgument(std::string("trajectory JSON: ") + e.what());
        }
        auto out = std::make_shared<T>();
        out->scene = std::make_shared<const S>(scene);
        out->trajectory = trajectory_from_json(j, scene);
        out->options.breakpoints = out->trajectory.input_breakpoints;
        out->name = "read from JSON";
        if constexpr (S::nu == 0) {
          out->trajectory.input = zero_input<S>();  // no input to lose
        } else {
          out->trajectory.input = [](double t, const VecT<double, 2 * S::nq>&, const Mode<S::nc>&) -> VecT<double, S::nu> {
            throw InvalidArgument(detail::concat("the trajectory was read from JSON, which does not hold its input law: "
                                                 "no input at t = ",
                                                 t, " (simulate it again, or polish its CSV, to analyse it)"));
          };
        }
        return out;
      },
      py::arg("scene"), py::arg("text"),
      "The trajectory that Trajectory.to_json(complete=True) wrote, rebuilt exactly for `scene` (its class must be "
      "the trajectory's); see saltus.read_trajectory, which also reads files. Raises saltus.InvalidArgument naming "
      "the key of a JSON it cannot rebuild from (not written complete, a missing key, a state of the wrong size, ...).");

  m.def("simulate", &simulate<S>, py::arg("scene"), py::arg("x0"), py::arg("t0"), py::arg("t_final"),
        py::arg("input") = py::none(), py::arg("options") = py::none(), simulate_doc);
}

/// A reference of the scene library as a trajectory (its C++ input law inside).

}  // namespace saltus::python
