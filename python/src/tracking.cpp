// Tracking designs along a reference with impacts, their stability check and the Monte Carlo
// validation (sensitivity/tracking.hpp), for the point mass (the guiding example: Example 3's
// impact, sliding and release; the periodic hop) and the plank-box:
//   lin = saltus.linearise(reference)                      LinearisedSystem (reference spreading, jump gains)
//   K = saltus.lqr_design(lin, Q, R, Q_final)              a GainSchedule (or saltus.constant_gains(lin, K))
//   design = saltus.tracking(lin, K)                       controller + closed-loop linearisation
//   design.check_stability(), design.monte_carlo(runs=200)
// The Monte Carlo batch runs a chunk [first, first + count) of a batch of `runs` perturbations,
// drawn exactly as the C++ monte_carlo draws them (one mt19937_64 stream from `seed`): chunks run
// anywhere (saltus.distributed: Dask workers) and MonteCarloReport.merge puts them back together
// into the report of the whole batch.
#include "common.hpp"

#include <saltus/sensitivity/linearisation.hpp>
#include <saltus/sensitivity/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <random>

namespace saltus::python {

namespace {

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

/// The summary of monte_carlo (tracking.hxx) from report.run: the same statistics in the same
/// order, so that a merged batch reports what one call over the whole batch reports (tested:
/// test_tracking.py compares a merged batch with one C++ call).
void summarise(MonteCarloReport& report, double horizon) {
  report.runs = static_cast<int>(report.run.size());
  report.failed = report.kept_event_sequence = report.grew = report.shrank = 0;
  report.failure_reasons.clear();
  report.max_log_discrepancy = 0.0;
  report.observed_rate_median = 0.0;
  std::map<std::string, int> reasons;
  std::vector<double> rates;
  report.observed_rate_max = report.predicted_rate_max = -std::numeric_limits<double>::infinity();
  for (const MonteCarloRun& r : report.run) {
    if (r.failed) {
      ++report.failed;
      ++reasons[r.reason];
      continue;
    }
    if (!r.kept_event_sequence) continue;
    ++report.kept_event_sequence;
    const double rate = std::log(r.observed) / horizon;
    rates.push_back(rate);
    report.observed_rate_max = std::max(report.observed_rate_max, rate);
    if (std::isfinite(r.predicted)) {
      report.predicted_rate_max = std::max(report.predicted_rate_max, std::log(r.predicted) / horizon);
      report.max_log_discrepancy = std::max(report.max_log_discrepancy, std::abs(std::log(r.observed / r.predicted)));
    }
    (r.observed > 1 ? report.grew : report.shrank) += 1;
  }
  if (!rates.empty()) {
    std::nth_element(rates.begin(), rates.begin() + static_cast<std::ptrdiff_t>(rates.size() / 2), rates.end());
    report.observed_rate_median = rates[rates.size() / 2];
  }
  if (rates.empty()) report.observed_rate_max = std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(report.predicted_rate_max)) report.predicted_rate_max = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [reason, count] : reasons) report.failure_reasons.push_back(detail::concat(count, " x ", reason));
}

PyMonteCarlo merge(std::vector<PyMonteCarlo> parts) {
  SALTUS_REQUIRE(!parts.empty(), "MonteCarloReport.merge: no reports");
  std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  PyMonteCarlo out;
  out.first = parts.front().first;
  out.batch_runs = parts.front().batch_runs;
  out.t0 = parts.front().t0;
  out.t_final = parts.front().t_final;
  int next = out.first;
  for (const PyMonteCarlo& p : parts) {
    SALTUS_REQUIRE(p.first == next, "MonteCarloReport.merge: the chunks do not follow each other (runs from ", next,
                   " expected, got a chunk from ", p.first, ")");
    SALTUS_REQUIRE(p.batch_runs == out.batch_runs && p.t0 == out.t0 && p.t_final == out.t_final,
                   "MonteCarloReport.merge: the chunks belong to different batches");
    out.report.run.insert(out.report.run.end(), p.report.run.begin(), p.report.run.end());
    out.report.seconds += p.report.seconds;
    out.report.threads = std::max(out.report.threads, p.report.threads);
    next += p.report.runs;
  }
  summarise(out.report, out.t_final - out.t0);
  return out;
}

py::tuple run_state(const MonteCarloRun& r) {
  return py::make_tuple(r.failed, r.reason, r.kept_event_sequence, r.events, r.observed, r.predicted);
}

MonteCarloRun run_from(const py::handle& h) {
  const auto t = h.cast<py::tuple>();
  MonteCarloRun r;
  r.failed = t[0].cast<bool>();
  r.reason = t[1].cast<std::string>();
  r.kept_event_sequence = t[2].cast<bool>();
  r.events = t[3].cast<int>();
  r.observed = t[4].cast<double>();
  r.predicted = t[5].cast<double>();
  return r;
}

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

template <Scene S>
StabilityReport check(PyTracking<S>& tr, const std::optional<Eigen::MatrixXd>& weight,
                      const std::optional<Eigen::MatrixXd>& output_weight, std::optional<double> t_final) {
  const StabilityOptions<S> o = stability_options<S>(weight, output_weight);
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(tr.mutex);
  return check_stability(*tr.closed_loop, o, t_final.value_or(-1.0));
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
                               std::uint64_t seed, int threads, std::optional<double> t_final, int first,
                               std::optional<int> count, const std::optional<Eigen::MatrixXd>& weight,
                               const std::optional<Eigen::MatrixXd>& output_weight) {
  constexpr int nx = 2 * S::nq;
  SALTUS_REQUIRE(runs >= 1, "monte_carlo: runs must be >= 1, got ", runs);
  const int n = count.value_or(runs - first);
  SALTUS_REQUIRE(first >= 0 && n >= 1 && first + n <= runs, "monte_carlo: the chunk [", first, ", ", first + n,
                 ") is not a non-empty part of the batch [0, ", runs, ")");
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
  if (t_final) o.t_final = *t_final;
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

template <Scene S>
void bind_scene_tracking(py::module_& m) {
  static constexpr int nx = 2 * S::nq;  // static: the lambdas use it without capture
  using Schedule = GainSchedule<S>;
  py::class_<Schedule>(m, class_name<S>("GainSchedule").c_str(),
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
          "times", [](const Schedule& s, int i) { return s.times(i); }, py::arg("segment"),
          "the sample times of segment i [s]");

  using L = PyLinearisation<S>;
  py::class_<L, std::shared_ptr<L>>(m, class_name<S>("Linearisation").c_str(),
                                    "The linearisation along a reference: its segments extended past their events "
                                    "(reference spreading) and the jump gain of every event.")
      .def_property_readonly("reference", [](const L& l) { return l.reference; })
      .def_property_readonly("segment_count", [](const L& l) { return l.system->segment_count(); })
      .def(
          "conewise", [](const L& l, int i) { return l.system->conewise(i); }, py::arg("event"),
          "event i is simultaneous: its gain is conewise (G_z, G_v of gains() are NaN there)")
      .def(
          "gains",
          [](const L& l) {
            py::list out;
            for (const auto& g : l.system->gains()) out.append(py::make_tuple(Eigen::MatrixXd(g.G_z), Eigen::MatrixXd(g.G_v)));
            return out;
          },
          "per event (G_z (nx, nx), G_v (nx, nu)) with the reference's input as a signal");

  using T = PyTracking<S>;
  py::class_<T, std::shared_ptr<T>>(m, class_name<S>("Tracking").c_str(),
                                    "A reference-spreading tracking design: the controller and its closed-loop "
                                    "linearisation along the reference.")
      .def_property_readonly("plant_options", [](const T& t) { return t.plant; })
      .def(
          "propagate",
          [](T& t, const Eigen::VectorXd& z0, double time) {
            const Vec<nx> z = to_state<S>(z0, "z0");
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
           py::arg("scale") = py::none(), py::arg("seed") = 20261130ULL, py::arg("threads") = 0,
           py::arg("t_final") = py::none(), py::arg("first") = 0, py::arg("count") = py::none(),
           py::arg("weight") = py::none(), py::arg("output_weight") = py::none(),
           "Closed-loop simulations from x(t0) + size d, d_j ~ N(0, scale_j^2) (a batch of `runs` directions drawn "
           "from `seed`), each compared with the first-order prediction. Runs the chunk [first, first + count) of "
           "the batch (default: all of it) on `threads` threads (0: all cores). Returns a MonteCarloReport; "
           "MonteCarloReport.merge joins chunks.")
      .def(
          "perturbations",
          [](const T&, int runs, const std::optional<Eigen::VectorXd>& scale, std::uint64_t seed) {
            Vec<nx> s = Vec<nx>::Ones();
            if (scale) s = to_state<S>(*scale, "scale");
            const auto d = draw<nx>(0, runs, s, seed);
            RowMatrix out(runs, nx);
            for (int r = 0; r < runs; ++r) out.row(r) = d[static_cast<std::size_t>(r)].transpose();
            return out;
          },
          py::arg("runs"), py::arg("scale") = py::none(), py::arg("seed") = 20261130ULL,
          "the directions d (runs, nx) that monte_carlo draws");

  m.def("linearise", &linearise<S>, py::arg("reference"), py::arg("spreading") = 0.1, py::arg("feedback") = "signal");
  m.def("lqr_design", &lqr<S>, py::arg("linearisation"), py::arg("Q") = py::none(), py::arg("R") = py::none(),
        py::arg("Q_final") = py::none(), py::arg("sample_step") = 1e-3);
  m.def(
      "constant_gains",
      [](const L& lin, const Eigen::MatrixXd& K) { return Schedule(lin.system->segment_count(), to_gain<S>(K)); },
      py::arg("linearisation"), py::arg("K"));
  m.def("tracking", &tracking<S>, py::arg("linearisation"), py::arg("gains"), py::arg("plant_options") = py::none());
}

}  // namespace

void bind_tracking(py::module_& m) {
  py::class_<StabilityReport>(m, "StabilityReport", "The verdict of a stability check along a finite reference.")
      .def_property_readonly("verdict", [](const StabilityReport& r) { return std::string(to_string(r.verdict)); },
                             "'stable' (upper bound of a(T) < 1), 'unstable' (lower bound > 1) or 'undecided'")
      .def_readonly("t0", &StabilityReport::t0)
      .def_readonly("t_final", &StabilityReport::t_final)
      .def_readonly("upper_bound", &StabilityReport::upper_bound, "of a(T) = |z(T)|_Wout / |z(t0)|_W")
      .def_readonly("lower_bound", &StabilityReport::lower_bound)
      .def_readonly("upper_rate", &StabilityReport::upper_rate, "log(upper_bound) / (T - t0), 1/s")
      .def_readonly("lower_rate", &StabilityReport::lower_rate, "1/s")
      .def_readonly("peak_upper", &StabilityReport::peak_upper)
      .def_readonly("peak_time", &StabilityReport::peak_time, "s")
      .def_readonly("tail_amplification", &StabilityReport::tail_amplification)
      .def_readonly("sequences", &StabilityReport::sequences)
      .def_readonly("exhaustive", &StabilityReport::exhaustive)
      .def_readonly("seconds", &StabilityReport::seconds)
      .def("__repr__",
           [](const StabilityReport& r) {
             return detail::concat("StabilityReport(", to_string(r.verdict), ", a(T) in [", r.lower_bound, ", ",
                                   r.upper_bound, "])");
           })
      .def(py::pickle(
          [](const StabilityReport& r) {
            return py::make_tuple(static_cast<int>(r.verdict), r.t0, r.t_final, r.upper_bound, r.lower_bound,
                                  r.upper_rate, r.lower_rate, r.peak_upper, r.peak_lower, r.peak_time,
                                  r.tail_amplification, r.tail_rate, r.sequences, r.exhaustive, r.off_nominal_pieces,
                                  r.seconds);
          },
          [](const py::tuple& t) {
            StabilityReport r;
            r.verdict = static_cast<StabilityVerdict>(t[0].cast<int>());
            double* fields[] = {&r.t0,         &r.t_final,   &r.upper_bound, &r.lower_bound,
                                &r.upper_rate, &r.lower_rate, &r.peak_upper, &r.peak_lower,
                                &r.peak_time,  &r.tail_amplification, &r.tail_rate};
            for (std::size_t k = 0; k < std::size(fields); ++k) *fields[k] = t[k + 1].cast<double>();
            r.sequences = t[12].cast<long>();
            r.exhaustive = t[13].cast<bool>();
            r.off_nominal_pieces = t[14].cast<int>();
            r.seconds = t[15].cast<double>();
            return r;
          }));

  py::class_<PeriodicStabilityReport>(m, "PeriodicStabilityReport",
                                      "The verdict of the periodic check: bounds on the spectral radius of the "
                                      "closed-loop monodromy over one period.")
      .def_property_readonly("verdict",
                             [](const PeriodicStabilityReport& r) { return std::string(to_string(r.verdict)); })
      .def_readonly("period", &PeriodicStabilityReport::period, "s")
      .def_readonly("spectral_radius_upper", &PeriodicStabilityReport::spectral_radius_upper)
      .def_readonly("spectral_radius_lower", &PeriodicStabilityReport::spectral_radius_lower)
      .def_readonly("eigenvalue_moduli", &PeriodicStabilityReport::eigenvalue_moduli)
      .def_readonly("seconds", &PeriodicStabilityReport::seconds);

  using MC = PyMonteCarlo;
  py::class_<MC>(m, "MonteCarloReport",
                 "Closed-loop runs [first, first + runs) of a Monte Carlo batch against the first-order prediction. "
                 "Rates are log(amplification) / (t_final - t0) in 1/s.")
      .def_property_readonly("first", [](const MC& r) { return r.first; })
      .def_property_readonly("batch_runs", [](const MC& r) { return r.batch_runs; })
      .def_property_readonly("t0", [](const MC& r) { return r.t0; })
      .def_property_readonly("t_final", [](const MC& r) { return r.t_final; })
      .def_property_readonly("runs", [](const MC& r) { return r.report.runs; })
      .def_property_readonly("failed", [](const MC& r) { return r.report.failed; })
      .def_property_readonly("kept_event_sequence", [](const MC& r) { return r.report.kept_event_sequence; })
      .def_property_readonly("failure_reasons", [](const MC& r) { return r.report.failure_reasons; })
      .def_property_readonly("observed_rate_max", [](const MC& r) { return r.report.observed_rate_max; })
      .def_property_readonly("observed_rate_median", [](const MC& r) { return r.report.observed_rate_median; })
      .def_property_readonly("predicted_rate_max", [](const MC& r) { return r.report.predicted_rate_max; })
      .def_property_readonly("max_log_discrepancy", [](const MC& r) { return r.report.max_log_discrepancy; })
      .def_property_readonly("grew", [](const MC& r) { return r.report.grew; })
      .def_property_readonly("shrank", [](const MC& r) { return r.report.shrank; })
      .def_property_readonly("seconds", [](const MC& r) { return r.report.seconds; },
                             "s: wall time of the simulations (merged: the sum over the chunks)")
      .def_property_readonly("threads", [](const MC& r) { return r.report.threads; })
      .def_property_readonly(
          "observed",
          [](const MC& r) {
            Eigen::VectorXd v(r.report.run.size());
            for (std::size_t k = 0; k < r.report.run.size(); ++k) v[static_cast<Eigen::Index>(k)] = r.report.run[k].observed;
            return v;
          },
          "(runs,) |x(T) - x_j(T)|_Wout / |eps d|_W of each run (0 for a failed run)")
      .def_property_readonly(
          "predicted",
          [](const MC& r) {
            Eigen::VectorXd v(r.report.run.size());
            for (std::size_t k = 0; k < r.report.run.size(); ++k) v[static_cast<Eigen::Index>(k)] = r.report.run[k].predicted;
            return v;
          },
          "(runs,) the first-order amplification of the same d")
      .def_property_readonly(
          "run_failed",
          [](const MC& r) {
            std::vector<bool> v;
            for (const auto& run : r.report.run) v.push_back(run.failed);
            return v;
          },
          "per run: it threw (reason in failure_reasons)")
      .def_property_readonly(
          "run_kept_event_sequence",
          [](const MC& r) {
            std::vector<bool> v;
            for (const auto& run : r.report.run) v.push_back(run.kept_event_sequence);
            return v;
          })
      .def_static("merge", &merge, py::arg("reports"),
                  "One report of consecutive chunks of one batch (in any order): runs concatenated, statistics "
                  "recomputed over all of them")
      .def("__repr__",
           [](const MC& r) {
             return detail::concat("MonteCarloReport(runs ", r.first, "..", r.first + r.report.runs, " of ",
                                   r.batch_runs, ": ", r.report.kept_event_sequence, " kept the event sequence, ",
                                   r.report.failed, " failed, observed rate max ", r.report.observed_rate_max,
                                   " 1/s)");
           })
      .def(py::pickle(
          [](const MC& r) {
            py::list runs;
            for (const auto& run : r.report.run) runs.append(run_state(run));
            return py::make_tuple(r.first, r.batch_runs, r.t0, r.t_final, r.report.seconds, r.report.threads, runs);
          },
          [](const py::tuple& t) {
            MC r;
            r.first = t[0].cast<int>();
            r.batch_runs = t[1].cast<int>();
            r.t0 = t[2].cast<double>();
            r.t_final = t[3].cast<double>();
            r.report.seconds = t[4].cast<double>();
            r.report.threads = t[5].cast<int>();
            for (const auto& h : t[6].cast<py::list>()) r.report.run.push_back(run_from(h));
            summarise(r.report, r.t_final - r.t0);
            return r;
          }));

  bind_scene_tracking<scenes::PointMass>(m);
  bind_scene_tracking<scenes::PlankBox>(m);
}

}  // namespace saltus::python
