// Writing the report of analyse_reference (reference_analysis.hpp) as JSON (to_json, write_json;
// nlohmann-json), as hybrid/vocabulary/trajectory_io.hpp writes a trajectory.
#pragma once

#include <saltus/sensitivity/analysis/reference_analysis.hpp>

#include <nlohmann/json.hpp>

#include <ostream>

namespace saltus {

/// The report as a JSON object; a stage's keys are written only when it completed:
///   linearisation_seconds
///   events               [{t (s), guards (their count), conewise; linear events: saltation_norm
///                        (|G_z|_2); conewise events: pieces, piece_norms (|G_z|_2 of each piece,
///                        in the order of ConewiseJumpGain::pieces), unrealisable_orders (their count),
///                        face_discontinuity (null when no face was compared)}]: every row built,
///                        also when the jump gains' stage failed after some of them
///   jump_gain_seconds
///   design, lqr_seconds  the tracking design's name and time
///   verdict              "stable", "unstable" or "undecided"
///   upper_bound, lower_bound   of a(T)
///   predicted_rate       log(upper_bound) / (T - t0), 1/s
///   peak_amplification   the largest sampled a(t) (upper bound)
///   check_seconds        the closed loop's linearisation and the check
///   monte_carlo          {runs, kept_event_sequence, failed, failure_reasons, departures (of the
///                        completed runs that left the event sequence, MonteCarloReport), grew, shrank (kept
///                        runs whose observed amplification is > 1, < 1), observed_rate_max (max
///                        over kept runs of log(observed) / (T - t0), 1/s), predicted_rate_max (the
///                        same of each run's first-order amplification), max_log_discrepancy (max
///                        |log(observed / first order)|), relative_to_nominal_run,
///                        nominal_run_deviation, nominal_run_max_deviation (the nominal run's error
///                        against the reference, state units), nominal_run_departure (why the runs
///                        were measured against the reference instead; MonteCarloReport),
///                        perturbation_size, simulation_seconds (the
///                        closed-loop runs), seconds (with the first-order predictions), threads,
///                        amplifications: {predicted, observed, kept_event_sequence} per run that
///                        did not fail (|z(T)| / |d| of the first order, |x(T) - x_j(T)| / |eps d|
///                        simulated, in the weights of MonteCarloOptions); with
///                        MonteCarloOptions::deviation_times also deviations: {t, predicted,
///                        observed}: per run that did not fail, the same ratios at each time t
///                        (MonteCarloRun::predicted_over_time, observed_over_time)}
///   agree                monte_carlo_agrees against predicted_rate
///   failure, failed_at   the message and the stage (to_string(AnalysisStage)) of a failed analysis
///   seconds              the whole analysis
/// Numbers keep their double values (a non-finite one is written as null); keys keep this order
/// (nlohmann::ordered_json).
template <Scene S>
nlohmann::ordered_json to_json(const ReferenceAnalysis<S>& analysis) {
  using json = nlohmann::ordered_json;
  const auto done = [&](AnalysisStage s) { return analysis.completed(s); };
  json j = json::object();
  if (done(AnalysisStage::Linearisation)) {
    j["linearisation_seconds"] = analysis.seconds.linearisation;
    j["events"] = json::array();
    for (const EventGainSummary& e : analysis.events) {
      json row{{"t", e.t}, {"guards", e.guards}, {"conewise", e.conewise}};
      if (e.conewise) {
        row["pieces"] = e.pieces;
        row["piece_norms"] = e.piece_norms;
        row["unrealisable_orders"] = e.unrealisable_orders;
        row["face_discontinuity"] = e.face_discontinuity ? json(*e.face_discontinuity) : json(nullptr);
      } else {
        row["saltation_norm"] = e.saltation_norm;
      }
      j["events"].push_back(std::move(row));
    }
  }
  if (done(AnalysisStage::JumpGains)) j["jump_gain_seconds"] = analysis.seconds.jump_gains;
  if (done(AnalysisStage::TrackingDesign)) {
    j["design"] = analysis.design_name;
    j["lqr_seconds"] = analysis.seconds.tracking_design;
  }
  if (done(AnalysisStage::StabilityCheck) && analysis.stability) {
    const StabilityReport& r = *analysis.stability;
    j["verdict"] = to_string(r.verdict);
    j["upper_bound"] = r.upper_bound;
    j["lower_bound"] = r.lower_bound;
    j["predicted_rate"] = r.upper_rate;
    j["peak_amplification"] = r.peak_upper;
    j["check_seconds"] = analysis.seconds.stability_check;
  }
  if (done(AnalysisStage::MonteCarlo) && analysis.monte_carlo) {
    const MonteCarloReport& m = *analysis.monte_carlo;
    j["monte_carlo"] = {{"runs", m.runs},
                        {"kept_event_sequence", m.kept_event_sequence},
                        {"failed", m.failed},
                        {"failure_reasons", m.failure_reasons},
                        {"departures", m.departures},
                        {"grew", m.grew},
                        {"shrank", m.shrank},
                        {"observed_rate_max", m.observed_rate_max},
                        {"predicted_rate_max", m.predicted_rate_max},
                        {"max_log_discrepancy", m.max_log_discrepancy},
                        {"relative_to_nominal_run", m.relative_to_nominal_run},
                        {"nominal_run_deviation", m.nominal_run_deviation},
                        {"nominal_run_max_deviation", m.nominal_run_max_deviation},
                        {"nominal_run_departure", m.nominal_run_departure},
                        {"perturbation_size", analysis.perturbation_size},
                        {"simulation_seconds", m.seconds},
                        {"seconds", analysis.seconds.monte_carlo},
                        {"threads", m.threads}};
    // Per run that did not fail: the first-order amplification |z(T)| / |d| against the observed
    // |x(T) - x_j(T)| / |eps d| (MonteCarloRun), and whether it kept the event sequence.
    json predicted = json::array(), observed = json::array(), kept = json::array();
    for (const MonteCarloRun& run : m.run) {
      if (run.failed) continue;
      predicted.push_back(run.predicted);
      observed.push_back(run.observed);
      kept.push_back(run.kept_event_sequence);
    }
    j["monte_carlo"]["amplifications"] = {{"predicted", std::move(predicted)},
                                          {"observed", std::move(observed)},
                                          {"kept_event_sequence", std::move(kept)}};
    if (!m.deviation_times.empty()) {
      json over_predicted = json::array(), over_observed = json::array();
      for (const MonteCarloRun& run : m.run) {
        if (run.failed) continue;
        over_predicted.push_back(run.predicted_over_time);
        over_observed.push_back(run.observed_over_time);
      }
      j["monte_carlo"]["deviations"] = {{"t", m.deviation_times},
                                        {"predicted", std::move(over_predicted)},
                                        {"observed", std::move(over_observed)}};
    }
    j["agree"] = analysis.agree;
  }
  if (analysis.failed_at) {
    j["failure"] = analysis.failure;
    j["failed_at"] = to_string(*analysis.failed_at);
  }
  j["seconds"] = analysis.seconds.total;
  return j;
}

/// to_json(analysis) on one line, then a newline.
template <Scene S>
void write_json(std::ostream& os, const ReferenceAnalysis<S>& analysis) {
  os << to_json(analysis).dump() << "\n";
}

}  // namespace saltus
