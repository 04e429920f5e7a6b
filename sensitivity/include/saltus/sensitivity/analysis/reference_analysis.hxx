// Definitions of reference_analysis.hpp (see there for the stages).
#pragma once

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/sensitivity/detail/dense.hpp>
#include <saltus/sensitivity/linearisation.hxx>
#include <saltus/sensitivity/tracking.hxx>

#include <chrono>
#include <cmath>
#include <ostream>

namespace saltus {

namespace detail {

// The arguments' own preconditions (reference_analysis.hpp, @throws), checked before any stage.
template <Scene S>
void require_analysable(const HybridTrajectory<S>& reference, const ReferenceAnalysisOptions<S>& options) {
  constexpr int nx = 2 * S::nq;
  const char* who = "analyse_reference: ";
  SALTUS_REQUIRE(reference.segment_count() >= 1, who, "the reference is an empty trajectory (no segments)");
  SALTUS_REQUIRE(reference.events.size() + 1 == reference.segments.size(), who, "the reference has ",
                 reference.segments.size(), " segments and ", reference.events.size(),
                 " events; a trajectory has one event fewer than segments");
  SALTUS_REQUIRE(static_cast<bool>(reference.input), who,
                 "the reference has no input law (HybridTrajectory::input is empty)");
  SALTUS_REQUIRE(std::isfinite(options.spreading) && options.spreading >= 0, who,
                 "options.spreading must be finite and >= 0 s, got ", options.spreading);
  const auto& E = options.stability.initial_subspace;
  SALTUS_REQUIRE(!E || E->cols() >= 1, who, "options.stability.initial_subspace has 0 columns (expected 1 to ", nx,
                 ")");
  const MonteCarloOptions<S>& mc = options.monte_carlo;
  SALTUS_REQUIRE(mc.runs >= 1, who, "options.monte_carlo.runs must be >= 1, got ", mc.runs);
  SALTUS_REQUIRE(std::isfinite(mc.size) && mc.size > 0, who, "options.monte_carlo.size must be > 0, got ", mc.size);
  const double t0 = reference.t_begin(), t1 = reference.t_end();
  SALTUS_REQUIRE(mc.t_final < 0 || (mc.t_final > t0 && mc.t_final <= t1), who, "options.monte_carlo.t_final = ",
                 mc.t_final, " s (the horizon) is outside the reference (", t0, ", ", t1, "]");
  SALTUS_REQUIRE(mc.weight == options.stability.weight, who,
                 "options.monte_carlo.weight differs from options.stability.weight: the batch would measure its "
                 "perturbations in another norm than the one the check bounds");
  const Mat<nx, nx> check_out = options.stability.output_weight.value_or(options.stability.weight);
  const Mat<nx, nx> batch_out = mc.output_weight.value_or(mc.weight);
  SALTUS_REQUIRE(check_out == batch_out, who,
                 "the output weights W_out of options.monte_carlo and options.stability differ: the batch would "
                 "measure another error than the one the check bounds");
  if (!E || mc.project) return;
  // The batch draws d with d_k = 0 where scale_k = 0: each perturbed coordinate must lie in range(E).
  const Eigen::MatrixXd P = *E * minimum_norm_solve(*E, Eigen::MatrixXd::Identity(nx, nx));  // onto range(E)
  for (int k = 0; k < nx; ++k)
    SALTUS_REQUIRE(mc.scale[k] == 0.0 || (Vec<nx>::Unit(k) - P.col(k)).norm() <= 1e-9, who,
                   "options.monte_carlo.scale perturbs coordinate ", k,
                   ", which options.stability.initial_subspace does not contain: the batch would test deviations "
                   "the verdict does not cover");
}

// The row of event e: its saltation norm, or its conewise gain's pieces and their norms.
template <Scene S>
EventGainSummary event_gain_summary(const LinearisedSystem<S>& open_loop, const Event<S>& event, int e) {
  EventGainSummary row;
  row.t = event.t;
  row.guards = static_cast<int>(event.guards().size());
  row.conewise = open_loop.conewise(e);
  if (!row.conewise) {
    row.saltation_norm = open_loop.gains()[e].G_z.operatorNorm();
    return row;
  }
  ConewiseJumpGain<S>& gain = open_loop.conewise_gain(e);
  row.pieces = gain.build_all();
  for (const ConewisePiece<S>* piece : gain.pieces()) row.piece_norms.push_back(piece->G_z.operatorNorm());
  row.unrealisable_orders = static_cast<int>(gain.unrealisable_orders().size());
  int faces = 0;
  const double jump = gain.face_discontinuity(200, &faces);
  if (faces > 0) row.face_discontinuity = jump;
  return row;
}

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace detail

template <Scene S>
ReferenceAnalysis<S> analyse_reference(const S& scene, const HybridTrajectory<S>& reference,
                                       const SimulationOptions& simulation, const ReferenceAnalysisOptions<S>& options) {
  using clock = std::chrono::steady_clock;
  using detail::seconds_since;
  detail::require_analysable(reference, options);
  ReferenceAnalysis<S> report;
  std::ostream* progress = options.progress;
  AnalysisStage stage = AnalysisStage::Linearisation;
  const auto start = clock::now();
  try {
    LinearisationOptions lo;
    lo.gains.feedback = FeedbackTreatment::Signal;  // the tracker replaces the reference's own law
    lo.simulation = simulation;
    lo.spreading.before = lo.spreading.after = options.spreading;
    auto t0 = clock::now();
    const LinearisedSystem<S> open_loop(scene, reference, lo);
    report.seconds.linearisation = seconds_since(t0);

    stage = AnalysisStage::JumpGains;
    t0 = clock::now();
    for (std::size_t e = 0; e < reference.events.size(); ++e)  // row by row: a failure keeps the rows before it
      report.events.push_back(detail::event_gain_summary(open_loop, reference.events[e], static_cast<int>(e)));
    report.seconds.jump_gains = seconds_since(t0);

    stage = AnalysisStage::TrackingDesign;
    if (progress) *progress << "analysis: " << reference.events.size() << " events linearised; LQR design\n";
    t0 = clock::now();
    report.design.emplace(lqr_design(open_loop, options.design.weights, options.design.lqr));
    report.design_name = options.design.name;
    report.seconds.tracking_design = seconds_since(t0);

    stage = AnalysisStage::StabilityCheck;
    t0 = clock::now();
    const ClosedLoopLinearisation<S> closed_loop(open_loop, report.design->gains);
    report.stability = check_stability(closed_loop, options.stability, options.monte_carlo.t_final);
    report.seconds.stability_check = seconds_since(t0);

    stage = AnalysisStage::MonteCarlo;
    const StabilityReport& verdict = *report.stability;
    if (progress)
      *progress << "analysis: " << to_string(verdict.verdict) << ", a(T) in [" << verdict.lower_bound << ", "
                << verdict.upper_bound << "]; Monte Carlo, " << options.monte_carlo.runs << " closed-loop runs\n";
    MonteCarloOptions<S> mc = options.monte_carlo;
    if (!mc.progress) mc.progress = progress;
    const ReferenceSpreadingController<S> controller(open_loop.reference(), report.design->gains);
    t0 = clock::now();
    report.monte_carlo = monte_carlo(scene, simulation, controller, closed_loop, mc);
    report.perturbation_size = mc.size;
    report.seconds.monte_carlo = seconds_since(t0);
    report.agree = monte_carlo_agrees(verdict.verdict, *report.monte_carlo, verdict.upper_rate);
  } catch (const Error& e) {
    report.failed_at = stage;
    report.failure = e.what();
  }
  report.seconds.total = seconds_since(start);
  return report;
}

}  // namespace saltus
