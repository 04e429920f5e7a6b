// Tracking designs along a reference with impacts, their stability check and the Monte Carlo
// validation (sensitivity/tracking.hpp), for the actuated scenes: the point mass (the guiding
// example: Example 3's impact, sliding and release; the periodic hop), the plank-box and the hopper
// (the unactuated bouncing ball and spatial box, nu = 0, have nothing to design):
//   lin = saltus.linearise(reference)                      LinearisedSystem (reference spreading, jump gains)
//   K = saltus.lqr_design(lin, Q, R, Q_final)              a GainSchedule (or saltus.constant_gains(lin, K))
//   design = saltus.tracking(lin, K)                       controller + closed-loop linearisation
//   design.check_stability(), design.monte_carlo(runs=200)
// The Monte Carlo batch runs a chunk [first, first + count) of a batch of `runs` perturbations,
// drawn exactly as the C++ monte_carlo draws them (one mt19937_64 stream from `seed`): chunks run
// anywhere (saltus.distributed: Dask workers) and MonteCarloReport.merge puts them back together
// into the report of the whole batch.
#include "common.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace saltus::python {

namespace {

void copy_nominal_run(const MonteCarloReport& from, MonteCarloReport& to) {
  to.relative_to_nominal_run = from.relative_to_nominal_run;
  to.nominal_run_deviation = from.nominal_run_deviation;
  to.nominal_run_max_deviation = from.nominal_run_max_deviation;
  to.nominal_run_departure = from.nominal_run_departure;
}

PyMonteCarlo merge(std::vector<PyMonteCarlo> parts) {
  SALTUS_REQUIRE(!parts.empty(), "MonteCarloReport.merge: no reports");
  std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  PyMonteCarlo out;
  out.first = parts.front().first;
  out.batch_runs = parts.front().batch_runs;
  out.t0 = parts.front().t0;
  out.t_final = parts.front().t_final;
  copy_nominal_run(parts.front().report, out.report);  // every chunk runs the same nominal run
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
  summarise_monte_carlo(out.report, out.t_final - out.t0);
  return out;
}

py::tuple run_state(const MonteCarloRun& r) {
  return py::make_tuple(r.failed, r.reason, r.kept_event_sequence, r.events, r.observed, r.predicted, r.departure);
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
  r.departure = t[6].cast<std::string>();
  return r;
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
      .def_property_readonly("departures", [](const MC& r) { return r.report.departures; },
                             "where the completed runs that did not keep the event sequence left it, with counts")
      .def_property_readonly("observed_rate_max", [](const MC& r) { return r.report.observed_rate_max; })
      .def_property_readonly("observed_rate_median", [](const MC& r) { return r.report.observed_rate_median; })
      .def_property_readonly("predicted_rate_max", [](const MC& r) { return r.report.predicted_rate_max; })
      .def_property_readonly("max_log_discrepancy", [](const MC& r) { return r.report.max_log_discrepancy; })
      .def_property_readonly("relative_to_nominal_run", [](const MC& r) { return r.report.relative_to_nominal_run; },
                             "whether the runs were measured against the nominal run (d = 0) rather than the reference")
      .def_property_readonly("nominal_run_deviation", [](const MC& r) { return r.report.nominal_run_deviation; },
                             "|x_0(T) - x_j(T)|_Wout of the nominal run: the reference's defect in closed loop (state units)")
      .def_property_readonly("nominal_run_max_deviation",
                             [](const MC& r) { return r.report.nominal_run_max_deviation; },
                             "the same, largest over T and the deviation times")
      .def_property_readonly("nominal_run_departure", [](const MC& r) { return r.report.nominal_run_departure; },
                             "why the runs were measured against the reference (empty when against the nominal run)")
      .def_property_readonly("grew", [](const MC& r) { return r.report.grew; })
      .def_property_readonly("shrank", [](const MC& r) { return r.report.shrank; })
      .def_property_readonly("seconds", [](const MC& r) { return r.report.seconds; },
                             "s: wall time of the simulations (merged: the sum over the chunks)")
      .def_property_readonly("threads", [](const MC& r) { return r.report.threads; })
      .def_property_readonly(
          "observed",
          [](const MC& r) {
            Eigen::VectorXd v(r.report.run.size());
            for (std::size_t k = 0; k < r.report.run.size(); ++k)
              v[static_cast<Eigen::Index>(k)] = r.report.run[k].failed ? std::numeric_limits<double>::quiet_NaN()
                                                                       : r.report.run[k].observed;
            return v;
          },
          "(runs,) |x(T) - x_j(T)|_Wout / |eps d|_W of each run, less the nominal run's error when "
          "relative_to_nominal_run (NaN for a failed run)")
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
            return py::make_tuple(r.first, r.batch_runs, r.t0, r.t_final, r.report.seconds, r.report.threads, runs,
                                  r.report.relative_to_nominal_run, r.report.nominal_run_deviation,
                                  r.report.nominal_run_max_deviation, r.report.nominal_run_departure);
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
            r.report.relative_to_nominal_run = t[7].cast<bool>();
            r.report.nominal_run_deviation = t[8].cast<double>();
            r.report.nominal_run_max_deviation = t[9].cast<double>();
            r.report.nominal_run_departure = t[10].cast<std::string>();
            summarise_monte_carlo(r.report, r.t_final - r.t0);
            return r;
          }));

  bind_scene_tracking<scenes::PointMass>(
      m, "PointMass",
      "The analysis of `reference` (a trajectory of the scene with its input law: a simulation, a library reference, "
      "an optimised reference) in one call, the C++ analyse_reference: (1) its linearisation with the segments "
      "extended by `spreading` s both ways (reference spreading), the input as a signal; (2) the jump gain of every "
      "event, reported by |G_z|_2 (a simultaneous event: its conewise gain, pieces and face continuity); (3) a "
      "time-varying LQR design: Q, Q_final (nx, nx) symmetric PSD, R (nu, nu) SPD (default identities), gains "
      "sampled every `sample_step` s; (4) the stability check on [t0, t_final] (default: the reference's end): "
      "bounds on a(T) = |z(T)|_Wout / |z(t0)|_W, weight W (nx, nx) SPD, output_weight W_out (nx, nx) PSD (default "
      "W), over the initial deviations in range(initial_subspace) (nx, r) of full column rank (default: all); (5) "
      "`runs` closed-loop simulations of the reference-spreading controller from x(t0) + size d, d_j ~ N(0, "
      "scale_j^2) (scale (nx,), default ones; projected orthogonally onto range(initial_subspace) when given; "
      "keep_initial_contacts projects each start onto the contacts closed at t0), drawn from `seed`, on `threads` "
      "threads (0: all cores), measured against the nominal run (relative_to_nominal_run) or the reference, and "
      "whether they agree with the verdict. `simulation`: the plant's options (default the reference's). "
      "`progress`: a callable given each progress line (str), or None for the logger 'saltus' (INFO). Returns a "
      "dict, the C++ report's JSON (reference_analysis_io.hpp): events [{t [s], guards, conewise, saltation_norm "
      "or pieces and piece_norms, unrealisable_orders, face_discontinuity}], design, verdict ('stable', 'unstable', 'undecided'), "
      "upper_bound, lower_bound, predicted_rate [1/s], peak_amplification, monte_carlo {runs, "
      "kept_event_sequence, failed, grew, shrank, observed_rate_max, max_log_discrepancy, seconds, ...}, agree, "
      "linearisation_seconds, jump_gain_seconds, lqr_seconds, check_seconds, seconds (the total), failed_at and failure when a stage threw (a grazing event, ...: the stages before "
      "it are kept); plus completed (bool) and gains (the design's GainSchedule, for tracking()). Raises "
      "saltus.InvalidArgument before any stage runs: weights, subspace or scale of the wrong shape or not "
      "finite, spreading < 0, sample_step <= 0, runs < 1, size <= 0, threads < 0, a seed outside [0, 2^64), "
      "t_final outside the reference, a progress that is not callable.");
  bind_scene_tracking<scenes::PlankBox>(m, "PlankBox");
  bind_scene_tracking<scenes::Hopper>(m, "Hopper");
}

}  // namespace saltus::python
