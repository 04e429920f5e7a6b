// The analysis of a reference in one call: what the jump gains, a tracking design and its
// stability check say about a reference with impacts, checked against nonlinear closed-loop
// simulations. The reference is a HybridTrajectory with its input law (HybridTrajectory::input),
// wherever it came from: the event-driven simulator, the re-simulation of an optimal or an
// imported reference (polish, hybrid/reference/resimulation.hpp). The stages, in order:
//
//  1. linearisation: the reference's segments extended by `spreading` seconds both ways
//     (reference spreading, hybrid/reference/reference_spreading.hpp) and linearised with the
//     reference's input as a signal (FeedbackTreatment::Signal: the tracking controller replaces
//     whatever law produced it; linearisation.hpp);
//  2. jump gains: per event its saltation matrix G_z (thesis C.37-C.39, jump_gain.hpp), reported
//     by its spectral norm |G_z|_2; at an event whose guards fire at once and admit no single
//     linear gain (two corners landing flat), the conewise gain with all its pieces built (each
//     reported by the spectral norm of its G_z), the orders no nearby motion realises, and the
//     measured continuity across shared cone faces (thesis appendix D, conewise_gain.hpp);
//  3. tracking design: a time-varying LQR along the reference with cost-to-go jumps (lqr_design,
//     tracking.hpp);
//  4. stability check: bounds on the amplification a(T) = |z(T)|_Wout / |z(t0)|_W of a first-order
//     deviation over the horizon, over the conewise pieces (check_stability, tracking.hpp);
//  5. Monte Carlo: nonlinear closed-loop simulations of the reference-spreading controller from
//     perturbed initial states (monte_carlo, tracking.hpp), and whether they agree with the
//     verdict (monte_carlo_agrees).
//
// A stage that throws saltus::Error (a grazing event, an impact problem without a solution, a
// numerical failure, a design the library refuses) ends the analysis: the report keeps what the
// stages before it computed (the events' rows built so far among them) and names the stage and
// the message. Writing the report as JSON: reference_analysis_io.hpp.
// Definitions in reference_analysis.hxx (compiled per scene, saltus/sensitivity/instantiate.hpp).
#pragma once

#include <saltus/sensitivity/tracking.hpp>

#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace saltus {

/// The tracking design of an analysis: a time-varying LQR along the reference.
template <Scene S>
struct TrackingDesignOptions {
  std::string name;        ///< for the report, e.g. "LQR, box Q = (10, 1), R = 0.01 I"
  LqrWeights<S> weights;   ///< Q, Q_final (2nq x 2nq), R (nu x nu); lqr_design checks them
  LqrOptions lqr;          ///< the gain schedule's sampling and the Riccati integration
};

/// What analyse_reference does, nested by stage. Shapes: nx = 2 nq, nu = S::nu.
template <Scene S>
struct ReferenceAnalysisOptions {
  /// s, >= 0: how far each segment is extended before its start and after its end (reference
  /// spreading; ExtensionOptions::before and after). Longer than the largest event shift of a
  /// perturbed run (monte_carlo fails a run that leaves the extension, by name).
  double spreading = 0.02;
  TrackingDesignOptions<S> design;
  /// The check's weights W (nx x nx, SPD) and W_out (nx x nx, PSD), its initial subspace E
  /// (nx x r, 1 <= r <= nx, full column rank), its sampling. Its horizon is monte_carlo.t_final.
  StabilityOptions<S> stability;
  /// The batch: runs (>= 1), perturbation size eps (> 0) and scale (nx), seed, threads, and
  /// t_final (s; default -1: the reference's end), the horizon of both the check and the batch.
  /// Its W and W_out must be the check's (the batch measures what the check bounds), and without
  /// a `project` function it must perturb only coordinates inside the check's initial subspace.
  MonteCarloOptions<S> monte_carlo;
  /// A line per stage and the batch's per-batch lines (when monte_carlo.progress is null); null:
  /// silent.
  std::ostream* progress = nullptr;
};

/// The stages of analyse_reference, in the order they run.
enum class AnalysisStage { Linearisation, JumpGains, TrackingDesign, StabilityCheck, MonteCarlo };

/// "linearisation", "jump gains", "tracking design", "stability check", "Monte Carlo".
const char* to_string(AnalysisStage stage);

/// The jump gain of one event of the reference.
struct EventGainSummary {
  double t = 0.0;           ///< s, the event time
  int guards = 0;           ///< guards that fired (Event::guards().size())
  bool conewise = false;    ///< simultaneous guards without a single linear gain
  /// |G_z|_2 of a linear gain (dimensionless in the scene's units); NaN at a conewise event.
  double saltation_norm = std::numeric_limits<double>::quiet_NaN();
  int pieces = 0;               ///< conewise: the linear pieces (ConewiseJumpGain::build_all)
  /// Conewise: |G_z|_2 of each piece, in the order ConewiseJumpGain::pieces() lists them (one per
  /// piece); empty at a linear event.
  std::vector<double> piece_norms;
  int unrealisable_orders = 0;  ///< conewise: orders no nearby motion realises
  /// Conewise: max |H_a(p) - H_b(p)| / |p| across shared cone faces over 200 sampled directions
  /// (ConewiseJumpGain::face_discontinuity); none when no face was compared or the event is linear.
  std::optional<double> face_discontinuity;
};

/// Wall-clock seconds of each stage (0 for a stage that did not complete).
struct AnalysisSeconds {
  double linearisation = 0.0;
  double jump_gains = 0.0;
  double tracking_design = 0.0;
  double stability_check = 0.0;  ///< the closed loop's linearisation and the check
  double monte_carlo = 0.0;      ///< the batch with its first-order predictions
  double total = 0.0;
};

/// The report of analyse_reference. A field of a stage that did not complete keeps its default
/// (events: the rows built before the failure).
template <Scene S>
struct ReferenceAnalysis {
  std::vector<EventGainSummary> events;  ///< one row per event of the reference, in order
  std::string design_name;               ///< TrackingDesignOptions::name
  std::optional<LqrDesign<S>> design;    ///< the gain schedule and cost-to-go
  /// The verdict on [t0, T], the bounds of a(T), the predicted rate upper_rate =
  /// log(upper_bound) / (T - t0) (1/s) and the peak amplification peak_upper.
  std::optional<StabilityReport> stability;
  std::optional<MonteCarloReport> monte_carlo;
  double perturbation_size = 0.0;  ///< eps of the batch (MonteCarloOptions::size)
  /// monte_carlo_agrees(verdict, batch, upper_rate): false unless the batch completed.
  bool agree = false;
  AnalysisSeconds seconds;
  std::optional<AnalysisStage> failed_at;  ///< the stage that threw; none: every stage completed
  std::string failure;                     ///< its message

  /// Every stage completed.
  bool completed() const { return !failed_at; }
  /// Stage `s` completed (it ran before the failing stage, or nothing failed).
  bool completed(AnalysisStage s) const { return !failed_at || s < *failed_at; }
};

/// Whether a Monte Carlo batch agrees with a stability check: some runs keep the event
/// sequence, and those all shrink (verdict stable) or one grows (unstable; an undecided verdict
/// passes this part), every observed amplification is the first-order one within 5 %
/// (max_log_discrepancy <= 0.05), and, when `compare_rate` (a finite-horizon bound on a(T); not for
/// a periodic orbit's asymptotic rate, which a finite batch does not bound from above), no
/// observed rate exceeds `predicted_rate` [1/s] by more than 1e-3 1/s.
bool monte_carlo_agrees(StabilityVerdict verdict, const MonteCarloReport& batch, double predicted_rate,
                        bool compare_rate = true);

/// Analyses `reference` (file comment): its jump gains, an LQR tracking design along it, the
/// design's stability check and a Monte Carlo batch of the closed loop, with the agreement.
///  - `scene`: the scene the reference moves in.
///  - `reference`: at least one segment, one event fewer than segments, its input law set (the
///    signal u_i(t) the design tracks; a scene without inputs has nothing to design and fails
///    at the tracking design).
///  - `simulation`: the options the reference was simulated with; the conewise gains re-resolve
///    its simultaneous events with them, and the batch's closed-loop runs use them.
///  - `options`: see ReferenceAnalysisOptions.
/// @throws InvalidArgument before any stage runs, naming the argument: an empty or inconsistent
/// trajectory, no input law, spreading < 0 or not finite, an initial subspace without columns, a
/// batch of runs < 1 or size <= 0, a horizon outside the reference, the batch's weights other
/// than the check's, a batch that perturbs coordinates outside the check's initial subspace.
/// A saltus::Error thrown by a stage is caught and reported (failed_at, failure); other
/// exceptions (std::bad_alloc) propagate.
template <Scene S>
ReferenceAnalysis<S> analyse_reference(const S& scene, const HybridTrajectory<S>& reference,
                                       const SimulationOptions& simulation, const ReferenceAnalysisOptions<S>& options);

}  // namespace saltus
