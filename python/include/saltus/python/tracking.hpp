// Binding a scene's linearisation and tracking designs for Python: linearise (with the first-order
// prediction and the state-transition matrix), lqr_design, constant_gains, tracking and the
// <scene>Tracking class (stability check, periodic check, Monte Carlo in chunks), and
// analyse_reference, the whole analysis of a reference in one call (the library's
// analyse_reference: jump gains, LQR design, stability check, Monte Carlo, agreement). The report
// classes (StabilityReport, PeriodicStabilityReport, MonteCarloReport) are saltus._saltus's.
#pragma once

#include <saltus/python/progress.hpp>
#include <saltus/python/trajectory.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/sensitivity/linearisation.hpp>
#include <saltus/sensitivity/tracking.hpp>

#include <Eigen/QR>

#include <limits>
#include <mutex>
#include <random>

namespace saltus::python {

template <Scene S>
struct PyLinearisation {
  std::shared_ptr<PyTrajectory<S>> reference;  // keeps the scene and the trajectory the system refers to
  std::unique_ptr<LinearisedSystem<S>> system;
};

template <Scene S>
struct PyTracking {
  std::shared_ptr<PyLinearisation<S>> linearisation;
  std::unique_ptr<ReferenceSpreadingController<S>> controller;
  std::unique_ptr<ClosedLoopLinearisation<S>> closed_loop;
  SimulationOptions plant;
  std::mutex mutex;  // ClosedLoopLinearisation is not thread-safe (conewise pieces built on demand)
};

/// A Monte Carlo report of runs [first, first + report.runs) of a batch of batch_runs.
struct PyMonteCarlo {
  MonteCarloReport report;
  int first = 0, batch_runs = 0;
  double t0 = 0.0, t_final = 0.0;  ///< s: the horizon of the rates
};

/// The perturbation directions d_r, r in [0, first + count), drawn as monte_carlo draws them.
template <int NX>
std::vector<Vec<NX>> draw(int first, int count, const Vec<NX>& scale, std::uint64_t seed) {
  std::vector<Vec<NX>> d(static_cast<std::size_t>(first + count));
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (auto& dr : d)
    for (int j = 0; j < NX; ++j) dr[j] = scale[j] * normal(rng);
  return d;
}

/// A random seed from Python: an integer (int, NumPy integer) in [0, 2^64). @throws
/// InvalidArgument (where pybind11's conversion would give a TypeError listing the overloads).
inline std::uint64_t to_seed(const py::object& seed) {
  PyObject* index = PyNumber_Index(seed.ptr());
  if (!index) PyErr_Clear();
  const auto i = py::reinterpret_steal<py::object>(index);
  SALTUS_REQUIRE(index && i >= py::int_(0) && i <= py::int_(std::numeric_limits<std::uint64_t>::max()),
                 "seed must be an integer in [0, 2^64), got ", py::repr(seed).cast<std::string>());
  return i.cast<std::uint64_t>();
}

template <Scene S>
std::shared_ptr<PyLinearisation<S>> linearise(std::shared_ptr<PyTrajectory<S>> reference, double spreading,
                                              const std::string& feedback) {
  SALTUS_REQUIRE(feedback == "signal" || feedback == "closed_loop", "feedback must be 'signal' or 'closed_loop', got '",
                 feedback, "'");
  SALTUS_REQUIRE(spreading > 0 && std::isfinite(spreading), "spreading must be > 0 s, got ", spreading);
  auto out = std::make_shared<PyLinearisation<S>>();
  out->reference = std::move(reference);
  LinearisationOptions o;
  o.gains.feedback = feedback == "signal" ? FeedbackTreatment::Signal : FeedbackTreatment::ClosedLoop;
  o.simulation = out->reference->options;
  o.spreading.before = o.spreading.after = spreading;
  py::gil_scoped_release release;
  out->system = std::make_unique<LinearisedSystem<S>>(*out->reference->scene, out->reference->trajectory, o);
  return out;
}

template <Scene S>
GainSchedule<S> lqr(const PyLinearisation<S>& lin, const std::optional<Eigen::MatrixXd>& Q,
                    const std::optional<Eigen::MatrixXd>& R, const std::optional<Eigen::MatrixXd>& Q_final,
                    double sample_step) {
  constexpr int nx = 2 * S::nq, nu = S::nu;
  LqrWeights<S> w;
  w.Q = to_square<nx>(Q, w.Q, "Q");
  w.R = to_square<nu>(R, w.R, "R");
  w.Q_final = to_square<nx>(Q_final, w.Q_final, "Q_final");
  LqrOptions o;
  SALTUS_REQUIRE(sample_step > 0 && std::isfinite(sample_step), "sample_step must be > 0 s, got ", sample_step);
  o.sample_step = sample_step;
  py::gil_scoped_release release;
  return lqr_design(*lin.system, w, o).gains;
}

template <Scene S>
Mat<S::nu, 2 * S::nq> to_gain(const Eigen::MatrixXd& K) {
  SALTUS_REQUIRE(K.rows() == S::nu && K.cols() == 2 * S::nq, "the gain has shape (", K.rows(), ", ", K.cols(),
                 "), expected (nu, nx) = (", S::nu, ", ", 2 * S::nq, ")");
  SALTUS_REQUIRE(K.allFinite(), "the gain K is not finite");
  return K;
}

template <Scene S>
std::shared_ptr<PyTracking<S>> tracking(std::shared_ptr<PyLinearisation<S>> lin, const GainSchedule<S>& gains,
                                        const std::optional<SimulationOptions>& plant) {
  auto out = std::make_shared<PyTracking<S>>();
  out->linearisation = std::move(lin);
  out->plant = plant.value_or(out->linearisation->reference->options);
  const LinearisedSystem<S>& ol = *out->linearisation->system;
  out->controller = std::make_unique<ReferenceSpreadingController<S>>(ol.reference(), gains);
  out->closed_loop = std::make_unique<ClosedLoopLinearisation<S>>(ol, gains);
  return out;
}

template <Scene S>
StabilityOptions<S> stability_options(const std::optional<Eigen::MatrixXd>& weight,
                                      const std::optional<Eigen::MatrixXd>& output_weight) {
  constexpr int nx = 2 * S::nq;
  StabilityOptions<S> o;
  o.weight = to_square<nx>(weight, o.weight, "weight");
  if (output_weight) o.output_weight = to_square<nx>(output_weight, o.weight, "output_weight");
  return o;
}

/// The horizon t_final given to check_stability or monte_carlo (None: the reference's end, which
/// the C++ calls take a negative value for): a given one must be finite and inside the reference,
/// so that a negative number is not silently read as "the end". @throws InvalidArgument.
template <Scene S>
double horizon(const PyTracking<S>& tr, const std::optional<double>& t_final, const char* who) {
  if (!t_final) return -1.0;
  const LinearisedSystem<S>& ol = *tr.linearisation->system;
  const double t0 = ol.t_begin(0), t_end = ol.t_end(ol.segment_count() - 1);
  SALTUS_REQUIRE(std::isfinite(*t_final) && *t_final > t0 && *t_final <= t_end, who,
                 ": t_final must be a time in the reference (", t0, ", ", t_end, "] s, got ", *t_final);
  return *t_final;
}

template <Scene S>
StabilityReport check(PyTracking<S>& tr, const std::optional<Eigen::MatrixXd>& weight,
                      const std::optional<Eigen::MatrixXd>& output_weight, std::optional<double> t_final) {
  const StabilityOptions<S> o = stability_options<S>(weight, output_weight);
  const double T = horizon(tr, t_final, "check_stability");
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(tr.mutex);
  return check_stability(*tr.closed_loop, o, T);
}

template <Scene S>
PeriodicStabilityReport check_periodic(PyTracking<S>& tr, double period, const std::optional<Eigen::MatrixXd>& weight) {
  const StabilityOptions<S> o = stability_options<S>(weight, std::nullopt);
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(tr.mutex);
  return check_periodic_stability(*tr.closed_loop, period, o);
}

template <Scene S>
PyMonteCarlo monte_carlo_chunk(PyTracking<S>& tr, int runs, double size, const std::optional<Eigen::VectorXd>& scale,
                               const py::object& seed_int, int threads, std::optional<double> t_final, int first,
                               std::optional<int> count, const std::optional<Eigen::MatrixXd>& weight,
                               const std::optional<Eigen::MatrixXd>& output_weight) {
  constexpr int nx = 2 * S::nq;
  SALTUS_REQUIRE(runs >= 1, "monte_carlo: runs must be >= 1, got ", runs);
  const std::uint64_t seed = to_seed(seed_int);
  const int n = count.value_or(runs - first);
  SALTUS_REQUIRE(first >= 0 && n >= 1 && first + n <= runs, "monte_carlo: the chunk [", first, ", ", first + n,
                 ") is not a non-empty part of the batch [0, ", runs, ")");
  SALTUS_REQUIRE(threads >= 0, "monte_carlo: threads must be >= 0 (0: all cores), got ", threads);
  MonteCarloOptions<S> o;
  o.runs = n;
  o.size = size;
  if (scale) {
    SALTUS_REQUIRE(scale->size() == nx, "monte_carlo: scale has size ", scale->size(), ", expected nx = ", nx);
    o.scale = *scale;
  }
  o.seed = seed;
  o.threads = threads;
  o.weight = to_square<nx>(weight, o.weight, "weight");
  if (output_weight) o.output_weight = to_square<nx>(output_weight, o.weight, "output_weight");
  o.t_final = horizon(tr, t_final, "monte_carlo");
  // The batch's directions d_first .. d_{first+n-1}: the library draws its own n and hands each to
  // `project` in order, which returns the batch's instead.
  auto d = std::make_shared<std::vector<Vec<nx>>>(draw<nx>(first, n, o.scale, seed));
  auto next = std::make_shared<int>(first);
  o.project = [d, next](const Vec<nx>&) { return (*d)[static_cast<std::size_t>((*next)++)]; };
  PyMonteCarlo out;
  out.first = first;
  out.batch_runs = runs;
  const LinearisedSystem<S>& ol = *tr.linearisation->system;
  out.t0 = ol.t_begin(0);
  out.t_final = o.t_final < 0 ? ol.t_end(ol.segment_count() - 1) : o.t_final;
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(tr.mutex);
  out.report = monte_carlo(*tr.linearisation->reference->scene, tr.plant, *tr.controller, *tr.closed_loop, o);
  return out;
}

/// analyse_reference from Python (the binding's docstring): the options from the arguments, the
/// report as a dict (its JSON, reference_analysis_io.hpp) with the design's gain schedule.
template <Scene S>
py::dict analyse(const std::shared_ptr<PyTrajectory<S>>& reference, const std::optional<Eigen::MatrixXd>& Q,
                 const std::optional<Eigen::MatrixXd>& R, const std::optional<Eigen::MatrixXd>& Q_final,
                 double spreading, double sample_step, const std::optional<Eigen::MatrixXd>& weight,
                 const std::optional<Eigen::MatrixXd>& output_weight,
                 const std::optional<Eigen::MatrixXd>& initial_subspace, int runs, double size,
                 const std::optional<Eigen::VectorXd>& scale, const py::object& seed, int threads,
                 std::optional<double> t_final, bool keep_initial_contacts, bool relative_to_nominal_run,
                 const std::optional<SimulationOptions>& simulation, const std::string& design_name,
                 py::object progress) {
  constexpr int nx = 2 * S::nq, nu = S::nu;
  const HybridTrajectory<S>& ref = reference->trajectory;
  ReferenceAnalysisOptions<S> o;
  o.spreading = spreading;
  o.design.name = design_name;
  o.design.weights.Q = to_square<nx>(Q, o.design.weights.Q, "Q");
  o.design.weights.R = to_square<nu>(R, o.design.weights.R, "R");
  o.design.weights.Q_final = to_square<nx>(Q_final, o.design.weights.Q_final, "Q_final");
  SALTUS_REQUIRE(sample_step > 0 && std::isfinite(sample_step), "sample_step must be > 0 s, got ", sample_step);
  o.design.lqr.sample_step = sample_step;
  o.stability.weight = to_square<nx>(weight, o.stability.weight, "weight");
  if (output_weight) o.stability.output_weight = to_square<nx>(output_weight, o.stability.weight, "output_weight");
  MonteCarloOptions<S>& mc = o.monte_carlo;
  mc.weight = o.stability.weight;
  mc.output_weight = o.stability.output_weight;
  if (initial_subspace) {
    const Eigen::MatrixXd& E = *initial_subspace;
    SALTUS_REQUIRE(E.rows() == nx && E.cols() >= 1 && E.cols() <= nx, "initial_subspace has shape (", E.rows(), ", ",
                   E.cols(), "), expected (nx, r) = (", nx, ", r) with 1 <= r <= ", nx);
    SALTUS_REQUIRE(E.allFinite(), "initial_subspace is not finite");
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(E);
    SALTUS_REQUIRE(qr.rank() == E.cols(), "initial_subspace must have full column rank ", E.cols(), ", has rank ",
                   qr.rank());
    o.stability.initial_subspace = E;
    // The batch perturbs inside range(E), as the check bounds: each draw projected orthogonally
    // (the first r columns of the rank check's Q span range(E): E Pi = Q R with Pi a permutation).
    const Eigen::MatrixXd basis = qr.householderQ() * Eigen::MatrixXd::Identity(nx, E.cols());
    const Mat<nx, nx> P = basis * basis.transpose();
    mc.project = [P](const Vec<nx>& d) { return Vec<nx>(P * d); };
  }
  mc.runs = runs;
  mc.size = size;
  if (scale) mc.scale = to_state<S>(*scale, "scale");
  SALTUS_REQUIRE(mc.scale.allFinite(), "scale is not finite");
  mc.seed = to_seed(seed);
  SALTUS_REQUIRE(threads >= 0, "threads must be >= 0 (0: all cores), got ", threads);
  mc.threads = threads;
  if (t_final) {
    SALTUS_REQUIRE(std::isfinite(*t_final) && *t_final > ref.t_begin() && *t_final <= ref.t_end(),
                   "t_final must be a time in the reference (", ref.t_begin(), ", ", ref.t_end(), "] s, got ",
                   *t_final);
    mc.t_final = *t_final;
  }
  mc.keep_initial_contacts = keep_initial_contacts;
  mc.relative_to_nominal_run = relative_to_nominal_run;
  PythonLines lines(progress_sink(std::move(progress)));
  std::ostream out(&lines);
  o.progress = &out;
  const SimulationOptions plant = simulation.value_or(reference->options);
  std::optional<ReferenceAnalysis<S>> a;
  {
    py::gil_scoped_release release;
    a.emplace(analyse_reference(*reference->scene, ref, plant, o));
    out.flush();
  }
  lines.rethrow();
  py::dict d = py::module_::import("json").attr("loads")(to_json(*a).dump()).template cast<py::dict>();
  d["completed"] = a->completed();
  if (a->design) d["gains"] = a->design->gains;
  return d;
}

/// Binds the classes <scene_name>GainSchedule, <scene_name>Linearisation, <scene_name>Tracking and
/// the overloads linearise, lqr_design, constant_gains, tracking, analyse_reference (docstring
/// `analyse_doc`: give it once, for the first scene bound) for the scene in m.
template <Scene S>
void bind_scene_tracking(py::module_& m, const std::string& scene_name, const char* analyse_doc = "") {
  static constexpr int nx = 2 * S::nq;  // static: the lambdas use it without capture
  using Schedule = GainSchedule<S>;
  py::class_<Schedule>(m, (scene_name + "GainSchedule").c_str(),
                       "A gain schedule K_i(t) (nu x nx) per reference segment i of a reference-spreading tracking "
                       "controller u = u_i(t) + K_i(t) (x - x_i(t)); linear between its sample times [s].")
      .def(py::init([](int segments, const Eigen::MatrixXd& K) {
             SALTUS_REQUIRE(segments >= 1, "segments must be >= 1, got ", segments);
             return Schedule(segments, to_gain<S>(K));
           }),
           py::arg("segments"), py::arg("K"), "the same constant gain K (nu, nx) on every segment")
      .def_property_readonly("segment_count", &Schedule::segment_count)
      .def(
          "gain", [](const Schedule& s, int i, double t) { return Eigen::MatrixXd(s(i, t)); }, py::arg("segment"),
          py::arg("t"), "K_i(t): (nu, nx)")
      .def(
          "times",
          [](const Schedule& s, int i) {
            SALTUS_REQUIRE(i >= 0 && i < s.segment_count(), "segment ", i, " out of range [0, ", s.segment_count(), ")");
            return s.times(i);
          },
          py::arg("segment"),
          "the sample times of segment i [s]");

  using L = PyLinearisation<S>;
  py::class_<L, std::shared_ptr<L>>(m, (scene_name + "Linearisation").c_str(),
                                    "The linearisation along a reference: its segments extended past their events "
                                    "(reference spreading) and the jump gain of every event.")
      .def_property_readonly("reference", [](const L& l) { return l.reference; })
      .def_property_readonly("segment_count", [](const L& l) { return l.system->segment_count(); })
      .def(
          "conewise",
          [](const L& l, int i) {
            const int n = static_cast<int>(l.reference->trajectory.events.size());
            SALTUS_REQUIRE(i >= 0 && i < n, "event index ", i, " out of range [0, ", n, ")");
            return l.system->conewise(i);
          },
          py::arg("event"),
          "event i is simultaneous: its gain is conewise (G_z, G_v of gains() are NaN there)")
      .def(
          "gains",
          [](const L& l) {
            py::list out;
            for (const auto& g : l.system->gains()) out.append(py::make_tuple(Eigen::MatrixXd(g.G_z), Eigen::MatrixXd(g.G_v)));
            return out;
          },
          "per event (G_z (nx, nx), G_v (nx, nu)) with the reference's input as a signal")
      .def(
          "predict",
          [](const L& l, const Eigen::VectorXd& z0, const Eigen::VectorXd& times, const std::optional<Eigen::VectorXd>& v) {
            const Vec<nx> z = to_state<S>(z0, "z0");
            SALTUS_REQUIRE(z.allFinite(), "predict: z0 is not finite");
            Vec<S::nu> vc = Vec<S::nu>::Zero();
            if (v) {
              SALTUS_REQUIRE(v->size() == S::nu, "v has size ", v->size(), ", expected nu = ", S::nu);
              SALTUS_REQUIRE(v->allFinite(), "predict: v is not finite");
              vc = *v;
            }
            const auto& ref = l.reference->trajectory;
            for (Eigen::Index k = 0; k < times.size(); ++k)
              SALTUS_REQUIRE(times[k] >= ref.t_begin() && times[k] <= ref.t_end(), "prediction time ", times[k],
                             " is outside the reference [", ref.t_begin(), ", ", ref.t_end(), "]");
            RowMatrix out(times.size(), nx);
            py::gil_scoped_release release;  // the reference's input law may be Python's
            const Prediction<S> p = l.system->predict(z, [vc](double) { return vc; });
            for (Eigen::Index k = 0; k < times.size(); ++k) {
              // Element by element: GCC 12 reports a false -Wstringop-overread on the packet copy of a
              // 2-vector into a row (nx = 2: a one-degree-of-freedom scene).
              const Vec<nx> zk = p.at(times[k]);
              for (int j = 0; j < nx; ++j) out(k, j) = zk[j];
            }
            return out;
          },
          py::arg("z0"), py::arg("times"), py::arg("v") = py::none(),
          "The first-order prediction z(t) (n, nx) at `times` (n,) [s] of the motion from x(t0) + eps z0 under u + eps "
          "v (v constant (nu,), default 0): x_eps(t) = x(t) + eps z(t) + O(eps^2), z taken on the nominal segment "
          "containing t (after the event at an event time). Raises saltus.SimultaneousActivation past a "
          "simultaneous event in a cone whose outcome is not the nominal one.")
      .def(
          "state_transition",
          [](const L& l, double t1, double t0) {
            py::gil_scoped_release release;
            return Eigen::MatrixXd(l.system->state_transition(t1, t0));
          },
          py::arg("t1"), py::arg("t0"),
          "The state-transition matrix (nx, nx) from t0 to t1 >= t0 [s] along the nominal segments, with the jump "
          "gains G_z at the events between. Raises saltus.SimultaneousActivation across a simultaneous event (the "
          "map is conewise there, not a matrix).");

  using T = PyTracking<S>;
  py::class_<T, std::shared_ptr<T>>(m, (scene_name + "Tracking").c_str(),
                                    "A reference-spreading tracking design: the controller and its closed-loop "
                                    "linearisation along the reference.")
      .def_property_readonly("plant_options", [](const T& t) { return t.plant; })
      .def(
          "propagate",
          [](T& t, const Eigen::VectorXd& z0, double time) {
            const Vec<nx> z = to_state<S>(z0, "z0");
            SALTUS_REQUIRE(z.allFinite(), "propagate: z0 is not finite");
            const LinearisedSystem<S>& ol = *t.linearisation->system;
            const double t0 = ol.t_begin(0), t_end = ol.t_end(ol.segment_count() - 1);
            SALTUS_REQUIRE(time >= t0 && time <= t_end, "propagate: t = ", time, " is outside the reference [", t0,
                           ", ", t_end, "]");
            std::lock_guard<std::mutex> lock(t.mutex);
            return Eigen::VectorXd(t.closed_loop->propagate(z, time));
          },
          py::arg("z0"), py::arg("t"), "the first-order closed-loop deviation z(t) (nx,) from z(t0) = z0 (nx,)")
      .def("check_stability", &check<S>, py::arg("weight") = py::none(), py::arg("output_weight") = py::none(),
           py::arg("t_final") = py::none(),
           "The stability check on [t0, t_final] (default: the reference's end): bounds on the amplification "
           "a(T) = |z(T)|_Wout / |z(t0)|_W of first-order deviations; weight W (nx, nx) SPD, output_weight W_out "
           "(nx, nx) PSD (default W). Returns a StabilityReport.")
      .def("check_periodic_stability", &check_periodic<S>, py::arg("period"), py::arg("weight") = py::none(),
           "Stability of a periodic reference of the given period [s]: bounds on the spectral radius of the "
           "closed-loop monodromy. Returns a PeriodicStabilityReport.")
      .def("monte_carlo", &monte_carlo_chunk<S>, py::arg("runs") = 200, py::arg("size") = 1e-4,
           py::arg("scale") = py::none(), py::arg("seed") = py::int_(20261130), py::arg("threads") = 0,
           py::arg("t_final") = py::none(), py::arg("first") = 0, py::arg("count") = py::none(),
           py::arg("weight") = py::none(), py::arg("output_weight") = py::none(),
           "Closed-loop simulations from x(t0) + size d, d_j ~ N(0, scale_j^2) (a batch of `runs` directions drawn "
           "from `seed`), each compared with the first-order prediction. Runs the chunk [first, first + count) of "
           "the batch (default: all of it) on `threads` threads (0: all cores). Returns a MonteCarloReport; "
           "MonteCarloReport.merge joins chunks.")
      .def(
          "perturbations",
          [](const T&, int runs, const std::optional<Eigen::VectorXd>& scale, const py::object& seed) {
            SALTUS_REQUIRE(runs >= 1, "perturbations: runs must be >= 1, got ", runs);
            Vec<nx> s = Vec<nx>::Ones();
            if (scale) s = to_state<S>(*scale, "scale");
            SALTUS_REQUIRE(s.allFinite(), "perturbations: the scale must be finite");
            const auto d = draw<nx>(0, runs, s, to_seed(seed));
            RowMatrix out(runs, nx);
            for (int r = 0; r < runs; ++r) out.row(r) = d[static_cast<std::size_t>(r)].transpose();
            return out;
          },
          py::arg("runs"), py::arg("scale") = py::none(), py::arg("seed") = py::int_(20261130),
          "the directions d (runs, nx) that monte_carlo draws");

  m.def("linearise", &linearise<S>, py::arg("reference"), py::arg("spreading") = 0.1, py::arg("feedback") = "signal");
  m.def("lqr_design", &lqr<S>, py::arg("linearisation"), py::arg("Q") = py::none(), py::arg("R") = py::none(),
        py::arg("Q_final") = py::none(), py::arg("sample_step") = 1e-3);
  m.def(
      "constant_gains",
      [](const L& lin, const Eigen::MatrixXd& K) { return Schedule(lin.system->segment_count(), to_gain<S>(K)); },
      py::arg("linearisation"), py::arg("K"));
  m.def("tracking", &tracking<S>, py::arg("linearisation"), py::arg("gains"), py::arg("plant_options") = py::none());
  m.def("analyse_reference", &analyse<S>, py::arg("reference"), py::arg("Q") = py::none(), py::arg("R") = py::none(),
        py::arg("Q_final") = py::none(), py::arg("spreading") = 0.02, py::arg("sample_step") = 1e-3,
        py::arg("weight") = py::none(), py::arg("output_weight") = py::none(),
        py::arg("initial_subspace") = py::none(), py::arg("runs") = 200, py::arg("size") = 1e-4,
        py::arg("scale") = py::none(), py::arg("seed") = py::int_(20261130), py::arg("threads") = 0,
        py::arg("t_final") = py::none(), py::arg("keep_initial_contacts") = false,
        py::arg("relative_to_nominal_run") = true, py::arg("simulation") = py::none(), py::arg("design_name") = "",
        py::arg("progress") = py::none(), analyse_doc);
}


}  // namespace saltus::python
