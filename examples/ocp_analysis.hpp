// The analysis of an optimal reference (`plank_box --json`): what the library's first three
// capabilities say about the motion the time-freezing OCP produced. The OCP's own solution is a
// discretisation; the analysis runs on its re-simulation by the event-driven simulator under the
// optimal input (ocp_report.hpp), a HybridTrajectory with exact events:
// - the jump gain of every event (its saltation matrix; for an event fired by several guards at
//   once the conewise gain, all pieces built, with the orders no nearby motion realises and the
//   measured continuity across shared cone faces);
// - a reference-spreading tracking design (time-varying LQR along the reference with cost-to-go
//   jumps, lqr_design) and its local stability check (check_stability: bounds on the
//   amplification of a deviation over the horizon, over the conewise pieces);
// - the check against nonlinear closed-loop simulations from perturbed initial states
//   (monte_carlo): do the runs that keep the event sequence grow or shrink as the verdict says,
//   and does the first-order amplification match the observed one.
#pragma once

#include <saltus/sensitivity/sensitivity.hpp>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <iostream>
#include <string>

namespace saltus::examples {

/// What the caller chooses: the design's weights and name, what the check and the Monte Carlo
/// batch measure and perturb, and how far the segments are extended (reference spreading).
template <Scene S>
struct ReferenceAnalysisSetup {
  std::string design;  ///< a name for the report, e.g. "LQR, box Q = (10, 1), R = 0.01 I"
  LqrWeights<S> weights;
  StabilityOptions<S> check;
  MonteCarloOptions<S> monte_carlo;
  double spreading = 0.02;  ///< s, LinearisationOptions::spreading before and after each segment
};

/// Never throws for a reference the library cannot analyse: a saltus::Error of any stage (a
/// grazing event, an impact problem without a solution, a numerical failure) ends the analysis
/// with {"failure": its message, "failed_at": the stage} and what was computed before it.
/// `simulation` must be the options the reference was simulated with (the conewise gains
/// re-resolve its simultaneous events with them). JSON: {"events": [{"t", "guards", "conewise",
/// "pieces", "unrealisable_orders", "face_discontinuity" (face_discontinuity(200): null when no
/// face was compared), "saltation_norm" (|G_z|_2, other events)}], "linearisation_seconds",
/// "jump_gain_seconds" (all pieces and the face samples), "design", "lqr_seconds", "verdict",
/// "upper_bound", "lower_bound", "predicted_rate", "peak_amplification", "check_seconds" (the
/// closed loop's linearisation and the check), "monte_carlo": {"runs", "kept_event_sequence",
/// "failed", "failure_reasons", "grew", "shrank", "observed_rate_max", "predicted_rate_max",
/// "max_log_discrepancy", "perturbation_size", "simulation_seconds" (the closed-loop runs),
/// "seconds" (with the first-order predictions), "threads"}, "seconds" (the whole analysis),
/// "agree"}; "agree" as in tracking_stability.cpp: some runs keep the event sequence, those all
/// shrink (verdict stable) or one grows (unstable), every observed amplification is the
/// first-order one within 5 % (|log(observed / predicted)| <= 0.05), and no observed rate exceeds
/// the predicted bound by more than 1e-3 1/s.
template <Scene S>
nlohmann::ordered_json analyse_reference(const S& scene, const HybridTrajectory<S>& reference,
                                         const SimulationOptions& simulation, const ReferenceAnalysisSetup<S>& setup,
                                         std::ostream* progress = &std::cerr) {
  using clock = std::chrono::steady_clock;
  const auto seconds_since = [](clock::time_point t0) {
    return std::chrono::duration<double>(clock::now() - t0).count();
  };
  nlohmann::ordered_json j;
  std::string stage = "linearisation";
  const auto start = clock::now();
  try {
    LinearisationOptions lo;
    lo.gains.feedback = FeedbackTreatment::Signal;  // the tracker replaces the reference's open-loop input
    lo.simulation = simulation;
    lo.spreading.before = lo.spreading.after = setup.spreading;
    auto t0 = clock::now();
    const LinearisedSystem<S> open_loop(scene, reference, lo);
    j["linearisation_seconds"] = seconds_since(t0);
    stage = "jump gains";
    t0 = clock::now();
    auto events = nlohmann::ordered_json::array();
    for (std::size_t e = 0; e < reference.events.size(); ++e) {
      const int i = static_cast<int>(e);
      nlohmann::ordered_json row{{"t", reference.events[e].t}, {"guards", reference.events[e].guards().size()},
                                 {"conewise", open_loop.conewise(i)}};
      if (open_loop.conewise(i)) {
        ConewiseJumpGain<S>& gain = open_loop.conewise_gain(i);
        row["pieces"] = gain.build_all();
        row["unrealisable_orders"] = gain.unrealisable_orders().size();
        int faces = 0;
        const double jump = gain.face_discontinuity(200, &faces);
        row["face_discontinuity"] = faces > 0 ? nlohmann::ordered_json(jump) : nlohmann::ordered_json(nullptr);
      } else {
        row["saltation_norm"] = open_loop.gains()[e].G_z.operatorNorm();
      }
      events.push_back(row);
    }
    j["events"] = events;
    j["jump_gain_seconds"] = seconds_since(t0);
    stage = "tracking design";
    if (progress) *progress << "analysis: " << reference.events.size() << " events linearised; LQR design\n";
    t0 = clock::now();
    const LqrDesign<S> lqr = lqr_design(open_loop, setup.weights);
    j["design"] = setup.design;
    j["lqr_seconds"] = seconds_since(t0);
    stage = "stability check";
    t0 = clock::now();
    const ClosedLoopLinearisation<S> closed_loop(open_loop, lqr.gains);
    const StabilityReport report = check_stability(closed_loop, setup.check, setup.monte_carlo.t_final);
    j["verdict"] = to_string(report.verdict);
    j["upper_bound"] = report.upper_bound;
    j["lower_bound"] = report.lower_bound;
    j["predicted_rate"] = report.upper_rate;
    j["peak_amplification"] = report.peak_upper;
    j["check_seconds"] = seconds_since(t0);
    stage = "Monte Carlo";
    if (progress)
      *progress << "analysis: " << to_string(report.verdict) << ", a(T) in [" << report.lower_bound << ", "
                << report.upper_bound << "]; Monte Carlo, " << setup.monte_carlo.runs << " closed-loop runs\n";
    MonteCarloOptions<S> mc = setup.monte_carlo;
    mc.progress = progress;
    const ReferenceSpreadingController<S> controller(open_loop.reference(), lqr.gains);
    t0 = clock::now();
    const MonteCarloReport m = monte_carlo(scene, simulation, controller, closed_loop, mc);
    j["monte_carlo"] = {{"runs", m.runs},
                        {"kept_event_sequence", m.kept_event_sequence},
                        {"failed", m.failed},
                        {"failure_reasons", m.failure_reasons},
                        {"grew", m.grew},
                        {"shrank", m.shrank},
                        {"observed_rate_max", m.observed_rate_max},
                        {"predicted_rate_max", m.predicted_rate_max},
                        {"max_log_discrepancy", m.max_log_discrepancy},
                        {"perturbation_size", mc.size},
                        {"simulation_seconds", m.seconds},
                        {"seconds", seconds_since(t0)},
                        {"threads", m.threads}};
    const bool verdict_ok = report.verdict == StabilityVerdict::Stable     ? m.shrank == m.kept_event_sequence
                            : report.verdict == StabilityVerdict::Unstable ? m.grew > 0
                                                                           : true;
    j["agree"] = m.kept_event_sequence > 0 && verdict_ok && m.max_log_discrepancy <= 0.05 &&
                 !(m.observed_rate_max > report.upper_rate + 1e-3);
  } catch (const Error& e) {
    j["failure"] = e.what();
    j["failed_at"] = stage;
  }
  j["seconds"] = seconds_since(start);
  return j;
}

}  // namespace saltus::examples
