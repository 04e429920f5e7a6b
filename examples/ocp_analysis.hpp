// The analysis of an optimal reference (`plank_box --json`): what the library's jump gains
// (sensitivity/jump_gain.hpp, conewise_gain.hpp) and tracking tools (sensitivity/tracking.hpp) say
// about the motion the time-freezing OCP produced. The OCP's own solution is a discretisation; the
// analysis runs on its re-simulation by the event-driven simulator under the optimal input
// (ocp_report.hpp), a HybridTrajectory with exact events:
// - the jump gain of every event: its saltation matrix G_z; where the guards of an event fire at
//   once and no single linear gain exists (LinearisedSystem throws SimultaneousActivation inside:
//   e.g. two corners landing or lifting off together), the conewise gain, all its pieces built,
//   with the orders no nearby motion realises and the measured continuity across shared cone
//   faces (guards that fire together but admit one linear gain, like two corners that stop
//   sliding together, keep a saltation matrix);
// - a reference-spreading tracking design (time-varying LQR along the reference with cost-to-go
//   jumps, lqr_design) and its local stability check (check_stability: bounds on the
//   amplification a(T) = |z(T)|_Wout / |z(t0)|_W of a first-order deviation over the horizon,
//   over the conewise pieces);
// - the check against nonlinear closed-loop simulations from perturbed initial states
//   (monte_carlo): do the runs that keep the event sequence grow or shrink as the verdict says,
//   and does the first-order amplification of each run's perturbation match the observed one.
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
/// Shapes: Q, Q_final, the check's W and W_out, the batch's W and W_out are 2nq x 2nq, R is
/// nu x nu, the check's initial subspace E is 2nq x k, the batch's scale has 2nq entries.
template <Scene S>
struct ReferenceAnalysisSetup {
  std::string design;  ///< a name for the report, e.g. "LQR, box Q = (10, 1), R = 0.01 I"
  LqrWeights<S> weights;
  StabilityOptions<S> check;
  /// Its t_final (default: the reference's end) is also the check's horizon; its progress stream
  /// is replaced by analyse_reference's `progress`.
  MonteCarloOptions<S> monte_carlo;
  double spreading = 0.02;  ///< s, LinearisationOptions::spreading before and after each segment
};

/// Whether a Monte Carlo batch agrees with the stability check (used by analyse_reference and
/// tracking_stability.cpp): some runs keep the event sequence, and those all shrink (verdict
/// stable) or one grows (unstable; an undecided verdict passes this part), every observed
/// amplification is the first-order one within 5 % (max_log_discrepancy <= 0.05), and, when
/// `compare_rate` (a finite-horizon bound on a(T); not for a periodic orbit's asymptotic rate,
/// which a finite batch does not bound from above), no observed rate exceeds `predicted_rate`
/// [1/s] by more than 1e-3 1/s.
inline bool monte_carlo_agrees(StabilityVerdict verdict, const MonteCarloReport& m, double predicted_rate,
                               bool compare_rate = true) {
  const bool verdict_ok = verdict == StabilityVerdict::Stable     ? m.shrank == m.kept_event_sequence
                          : verdict == StabilityVerdict::Unstable ? m.grew > 0
                                                                  : true;
  const bool below_bound = !compare_rate || !(m.observed_rate_max > predicted_rate + 1e-3);
  return m.kept_event_sequence > 0 && verdict_ok && m.max_log_discrepancy <= 0.05 && below_bound;
}

/// Catches every saltus::Error (a grazing event, an impact problem without a solution, a
/// numerical failure, a design the library refuses): the analysis then ends with {"failure": its
/// message, "failed_at": the stage, one of "linearisation", "jump gains", "tracking design",
/// "stability check", "Monte Carlo"} and keeps what was computed before (the events' rows built so
/// far among them). Other exceptions (std::bad_alloc) propagate. `simulation` must be the options
/// the reference was simulated with (the conewise gains re-resolve its simultaneous events with
/// them); `progress`: a few lines and Monte Carlo's per-batch lines, null for none.
/// JSON: {"events": [{"t", "guards" (their count), "conewise", conewise events: "pieces" (all of
/// them, ConewiseJumpGain::build_all), "unrealisable_orders" (their count),
/// "face_discontinuity" (ConewiseJumpGain::face_discontinuity over 200 sampled directions:
/// max |H_a(p) - H_b(p)| / |p| across shared faces; null when no face was compared); other
/// events: "saltation_norm" (|G_z|_2)}], "linearisation_seconds", "jump_gain_seconds", "design",
/// "lqr_seconds", "verdict" ("stable", "unstable", "undecided"), "upper_bound", "lower_bound" (of
/// a(T)), "predicted_rate" (log(upper_bound) / (T - t0), 1/s), "peak_amplification" (the largest
/// sampled a(t)), "check_seconds" (the closed loop's linearisation and the check), "monte_carlo":
/// {"runs", "kept_event_sequence", "failed", "failure_reasons", "grew", "shrank" (kept runs whose
/// observed amplification is > 1, < 1), "observed_rate_max" (max over kept runs of
/// log(observed) / (T - t0)), "predicted_rate_max" (the same of each run's first-order
/// amplification), "max_log_discrepancy" (max |log(observed / first order)|),
/// "perturbation_size", "simulation_seconds" (the closed-loop runs), "seconds" (with the
/// first-order predictions), "threads"}, "seconds" (the whole analysis), "agree"
/// (monte_carlo_agrees against predicted_rate)}.
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
    j["events"] = nlohmann::ordered_json::array();  // filled row by row: a failure keeps the rows before it
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
      j["events"].push_back(row);
    }
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
    j["agree"] = monte_carlo_agrees(report.verdict, m, report.upper_rate);
  } catch (const Error& e) {
    j["failure"] = e.what();
    j["failed_at"] = stage;
  }
  j["seconds"] = seconds_since(start);
  return j;
}

}  // namespace saltus::examples
