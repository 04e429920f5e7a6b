// Binding a scene's jump gains for Python: jump_gains(trajectory) -> one JumpGain per event, and
// conewise_gain(trajectory, event) -> the conewise, positively homogeneous gain of a simultaneous
// event (its pieces, cones and evaluate). The classes JumpGain and ConewisePiece are
// saltus._saltus's.
#pragma once

#include <saltus/python/trajectory.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/jump_gain.hpp>

#include <mutex>

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


/// One piece of a conewise gain as Python sees it (scene-independent: dynamic sizes).
struct PyConewisePiece {
  std::vector<std::vector<py::tuple>> order;  ///< the micro-events in order: groups of (contact, name, kind)
  Eigen::MatrixXd G_z, G_v;                   ///< (nx, nx), (nx, nu)
  Eigen::MatrixXd cone_z, cone_v;             ///< (rows, nx), (rows, nu): the cone is cone_z z + cone_v v >= 0
  Eigen::VectorXd x_plus;                     ///< (nx,): the post-event state of this order (zeroth order)
  std::string mode_after;
  bool nominal_outcome = true;  ///< x_plus and mode_after are the nominal event's
};

/// The conewise gain of one simultaneous event, with the trajectory it belongs to (the gain copies
/// the event and the law; the scene is the trajectory's).
template <Scene S>
struct PyConewiseGain {
  std::shared_ptr<PyTrajectory<S>> reference;
  std::unique_ptr<ConewiseJumpGain<S>> gain;
  std::mutex mutex;  // pieces are built on demand
};

template <Scene S>
PyConewisePiece piece_of(const PyTrajectory<S>& t, const ConewisePiece<S>& p) {
  PyConewisePiece out;
  for (const auto& group : p.order) {
    std::vector<py::tuple> g;
    for (const Guard& guard : group)
      g.push_back(py::make_tuple(guard.contact, t.scene->contact(guard.contact).name, to_string(guard.kind)));
    out.order.push_back(std::move(g));
  }
  out.G_z = p.G_z;
  out.G_v = p.G_v;
  out.cone_z = p.cone_z;
  out.cone_v = p.cone_v;
  out.x_plus = p.x_plus;
  out.mode_after = describe(*t.scene, p.mode_after);
  out.nominal_outcome = p.nominal_outcome;
  return out;
}

template <Scene S>
Vec<S::nu> to_input(const std::optional<Eigen::VectorXd>& v) {
  if (!v) return Vec<S::nu>::Zero();
  SALTUS_REQUIRE(v->size() == S::nu, "v has size ", v->size(), ", expected nu = ", S::nu);
  return *v;
}

/// Binds the overloads jump_gains(trajectory: <scene>Trajectory, ...) and conewise_gain(...), and the
/// class <scene_name>ConewiseGain, in m.
template <Scene S>
void bind_jump_gains_of(py::module_& m, const std::string& scene_name, const char* doc = "",
                        const char* conewise_doc = "") {
  using C = PyConewiseGain<S>;
  m.def("jump_gains", &gains_of<S>, py::arg("trajectory"), py::arg("feedback") = "closed_loop",
        py::arg("grazing_threshold") = 1e-8, doc);
  py::class_<C, std::shared_ptr<C>>(m, (scene_name + "ConewiseGain").c_str(),
                                    "The conewise, positively homogeneous jump gain of a simultaneous event: one "
                                    "linear piece z+ = G_z z- + G_v v per activation order of its guards, on the cone "
                                    "of deviations (z-, v) that realise that order.")
      .def_property_readonly("t", [](const C& c) { return c.gain->t(); }, "s: the event time")
      .def(
          "build_all",
          [](C& c) {
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> lock(c.mutex);
            return c.gain->build_all();
          },
          "builds every piece; returns their number")
      .def_property_readonly(
          "pieces",
          [](C& c) {
            std::lock_guard<std::mutex> lock(c.mutex);
            std::vector<PyConewisePiece> out;
            for (const ConewisePiece<S>* p : c.gain->pieces()) out.push_back(piece_of(*c.reference, *p));
            return out;
          },
          "the pieces built so far (build_all() builds all of them)")
      .def(
          "piece",
          [](C& c, const Eigen::VectorXd& z, const std::optional<Eigen::VectorXd>& v) {
            const Vec<2 * S::nq> zs = to_state<S>(z, "z");
            const Vec<S::nu> vs = to_input<S>(v);
            std::lock_guard<std::mutex> lock(c.mutex);
            return piece_of(*c.reference, c.gain->piece(zs, vs));
          },
          py::arg("z"), py::arg("v") = py::none(), "the piece whose cone contains (z- (nx,), v (nu,))")
      .def(
          "evaluate",
          [](C& c, const Eigen::VectorXd& z, const std::optional<Eigen::VectorXd>& v) {
            const Vec<2 * S::nq> zs = to_state<S>(z, "z");
            const Vec<S::nu> vs = to_input<S>(v);
            std::lock_guard<std::mutex> lock(c.mutex);
            return Eigen::VectorXd(c.gain->evaluate(zs, vs));
          },
          py::arg("z"), py::arg("v") = py::none(), "z+ (nx,) of the deviation z- (nx,) and the input deviation v (nu,)");
  m.def(
      "conewise_gain",
      [](std::shared_ptr<PyTrajectory<S>> t, int event) {
        const int n = static_cast<int>(t->trajectory.events.size());
        SALTUS_REQUIRE(event >= 0 && event < n, "event index ", event, " out of range [0, ", n, ")");
        auto out = std::make_shared<C>();
        out->reference = std::move(t);
        ConewiseGainOptions o;
        o.simulation = out->reference->options;
        out->gain = std::make_unique<ConewiseJumpGain<S>>(*out->reference->scene,
                                                          out->reference->trajectory.events[static_cast<std::size_t>(event)],
                                                          out->reference->trajectory.input, o);
        return out;
      },
      py::arg("trajectory"), py::arg("event"), conewise_doc);
}

}  // namespace saltus::python
