// Tracking design along a reference with impacts, and the local stability of the closed loop
// (reference spreading: thesis 3.1.2; appendix C for the jumps, appendix D for simultaneous ones).
//
// The controller. A reference-spreading tracking controller compares the plant with the reference
// segment that has seen the same events, whatever the time (hybrid/reference/reference_spreading.hpp):
//     u = u_i(t) + K_i(t) (x - x_i(t)),                                                     (RS)
// i the reference segment the plant is in, x_i, u_i the extended segment i (past its nominal
// interval by its own mode's flow and input), K_i(t) (nu x nx) a gain schedule per segment. The
// index i advances at the plant's own events (Simulator::run with a SegmentedInputLaw), so an early
// or late impact never makes the controller push the plant towards the other side of the jump.
// Simultaneous reference events (a box landing flat) reach the plant as several micro-events a
// time O(eps) apart; between the first and the last of them (the intermediate phase: the plant's
// mode is neither the ante- nor the post-event one) the controller applies the ante-event
// feedforward u_i(t) without feedback. Why: in the intermediate phase x - x_i and x - x_{i+1}
// differ from zero by O(1) in velocity, so any feedback would act with an O(1) input for an
// O(eps) time and move the post-event state at first order, which the conewise gain (built with
// the reference's input law in the intermediate modes, conewise_gain.hpp) does not contain. The
// phase ends when the plant's mode is the reference's post-event mode. The same intermediate phase
// covers a micro-event of the plant ahead of a reference event that opens or closes a contact: an
// event after which the plant keeps the segment's closed contacts (before and after it), while the
// reference's next event changes them. Two kinds: a friction transition (a slip onset a
// microsecond before a release from stick), and a bounce (a touchdown whose impact leaves the
// contact open again, ahead of the reference's touchdown). A long flight after such a bounce is
// flown under u_i(t) alone and ends far from the reference, so the Monte Carlo batch counts a
// run that bounced as a departure (MonteCarloRun::kept_event_sequence), not as a kept run that
// grew (measured on a refined hopper whose touchdown bounced in the simulator: all 200 runs;
// with the bounce advancing the segment instead, the default hopper's runs chattered to the
// integrator's step limit, 45 of the first 50 failed, at 8.5 s a run).
// A release from stick whose perturbed force leaves the friction cone a microsecond before lambda_n
// reaches 0 reaches the plant as a slip onset and then the release (measured on the refined hopper:
// before this rule the controller counted the slip onset as the release and tracked the stance
// after the flight during that flight). The controller then applies u_i(t) alone until the plant
// reaches the post-event mode, as in the intermediate phase (measured on that batch of 200 runs:
// with u_i(t) alone 51 runs kept the events and all shrank, as predicted; with the segment's
// feedback law in that phase instead, none did, every run stalled at the touchdown after that
// release). A plant event that opens or closes a contact (an unplanned touchdown) is never
// absorbed so: it advances the segment, and the Monte Carlo check flags it.
// Beyond the extended interval of its segment the controller holds the reference at the
// extension's end. The integrator's trial stages reach there (a step that crosses the plant's
// event evaluates the pre-event law past it, up to a step length; the error control judges
// those stages like any other); a plant whose event itself lies beyond the extension would be
// compared with a held state, so monte_carlo() fails such a run by name: make the extensions
// (ExtensionOptions::before/after of the LinearisedSystem) longer than the largest event shift.
//
// The closed-loop linearisation. With the deviation z = x - x_i(t) from the extended segment the
// plant is in (to first order, thesis C.39 with v = K z):
//     flow of segment i:  z' = (A_i(t) + B_i(t) K_i(t)) z,  A_i = df_i/dx, B_i = df_i/du at (x_i, u_i);
//     event i (at t_i*):  z+ = (G_z^i + G_v^i K_i(t_i*)) z-                                  (CL)
// G_z, G_v the open-loop jump gains of the reference (jump_gain.hpp, C.37-C.38, with the reference's
// input as a signal: FeedbackTreatment::Signal). Why the feedback enters the jump only through
// G_v K: the controller acts on the perturbed motion during the O(eps) time between the nominal
// and the perturbed event with an O(eps) correction K z, an O(eps^2) effect; it enters at first
// order only where a guard depends on the input (a release lambda_n(x, u) = 0 sees u = u_i + K z).
// At a simultaneous event the map is conewise: the piece whose cone contains (z-, K z-) applies,
// with G_z + G_v K (the pieces' cones and gains of ConewiseJumpGain).
//
// The stability check (finite reference). In weighted norms |z|_W = sqrt(z' W z) (W SPD, the
// initial deviation) and |z|_Wout (W_out PSD, what the design regulates; W by default), the
// amplification of the reference-spreading error from t0 to t is a(t) = |z(t)|_Wout / |z(t0)|_W
// over first-order deviations. Without simultaneous events the map is the matrix Phi(t, t0) and
// sup a(t) = |Phi(t, t0)|_{W -> Wout} = |Wout^(1/2) Phi L'^-1|_2 (W = L L'); on a subspace
// range(E) of initial deviations, |Wout^(1/2) Phi E R^-1|_2 with L' E = Q R (thin QR). With conewise events every deviation follows one sequence of pieces,
// so sup a(t) <= max over piece sequences s of |Phi_s(t, t0)|_W (the upper bound, exhaustive over
// the sequences); the lower bound is the largest a(t) realised by the conewise map itself on
// candidate deviations (the top right-singular vectors of every Phi_s, both signs, and random
// directions). Verdict on [t0, T]: stable when the upper bound of a(T) is below 1 (every
// first-order deviation is smaller at the end than at the start: the design contracts over the
// horizon), unstable when the lower bound is above 1, undecided between. The rates quoted are
// log(a(T)) / (T - t0) (1/s). The largest amplification over the horizon (the peak, sampled at
// `samples_per_segment` times per segment) and the decay after the last event, a_tail =
// |Phi(T, t_last)|_W (the terminal regulator alone), are reported beside the verdict.
//
// Periodic references (a hop cycle: a reference whose state and input repeat with period P, so
// that the deviation after one period is the monodromy map M of the closed loop). Linear (no
// simultaneous event in a period): stable iff the spectral radius rho(M) < 1. Conewise: the
// monodromies M_s of the piece sequences s of one period bound the growth rate of every realised
// product by their joint spectral radius, for which, with products of length k (Jungers, The Joint
// Spectral Radius, Springer LNCIS 385, 2009, Proposition 1.6, the "three members inequality"),
//     max_{products p of length k} rho(p)^(1/k) <= JSR <= max_{products p of length k} |p|_W^(1/k);
// the upper bound reported is the smallest right-hand side for k = 1..jsr_depth, the lower bound
// the largest rho(M_s) among the sequences s that repeat themselves: M_s has a real dominant
// eigenvector (eigenvalue > 0) whose propagation through one period follows s, so that the
// deviation along it grows exactly like rho(M_s)^n. Verdict: stable when upper < 1, unstable when
// lower > 1, undecided between (and when no sequence repeats itself, the lower bound is 0).
//
// Monte Carlo (monte_carlo below): nonlinear closed-loop simulations from x(t0) + eps d, d drawn
// from a distribution, on all cores (std::thread, one simulator per thread), with the observed
// amplification |x(T) - x_j(T)|_W / |eps d|_W per run (j the reference segment the plant ends in;
// by default less the nominal run's own error, MonteCarloOptions::relative_to_nominal_run) beside
// the first-order one of the same d, and a progress line per batch.
//
// Sources: reference spreading (Rijnen, Saccon, Nijmeijer; thesis chapter 3 and 3.1.2), jump
// gains (thesis C.37-C.42, jump_gain.hpp), conewise gains (thesis appendix D, conewise_gain.hpp),
// the LQR cost-to-go jump (below, lqr_design).
#pragma once

#include <saltus/sensitivity/linearisation.hpp>

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace saltus {

/// The plant saw an event the reference does not have (more events than the reference has
/// segments, or a mode that is neither the reference's next nor an intermediate one of a
/// simultaneous event): reference spreading has no segment to compare with.
class UnplannedEvent : public Error {
 public:
  using Error::Error;
};

/// A gain schedule K_i(t) (nu x nx, u = ... + K (x - x_i)) per segment i of a reference: samples
/// in time, linear interpolation between them, held constant before the first and after the
/// last (so it is defined on the whole extended segment). Evaluation allocates nothing.
template <Scene S>
class GainSchedule {
 public:
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  using Gain = Mat<nu, nx>;

  GainSchedule() = default;
  /// `segments` segments, each with the constant gain K.
  GainSchedule(int segments, const Gain& K);
  /// One constant gain per segment.
  explicit GainSchedule(std::vector<Gain> per_segment);

  int segment_count() const { return static_cast<int>(segments_.size()); }
  /// Replaces segment i's samples: times strictly increasing (at least one), one gain per time.
  /// @throws InvalidArgument (sizes, order, non-finite gains, i out of range)
  void set_samples(int i, std::vector<double> times, std::vector<Gain> gains);
  /// K_i(t). @throws InvalidArgument if i is out of range.
  Gain operator()(int i, double t) const;
  const std::vector<double>& times(int i) const { return segments_.at(i).times; }
  const std::vector<Gain>& gains(int i) const { return segments_.at(i).gains; }

 private:
  struct Samples {
    std::vector<double> times;
    std::vector<Gain> gains;
  };
  std::vector<Samples> segments_;
};

/// The gain of a PD law u = ... - Kp (q - q_i) - Kd (v - v_i): K = -[Kp, Kd] (Kp, Kd: nu x nq,
/// N/m and N s/m for translations, N m/rad and N m s/rad for rotations).
template <Scene S>
Mat<S::nu, 2 * S::nq> pd_gain(const Mat<S::nu, S::nq>& Kp, const Mat<S::nu, S::nq>& Kd) {
  Mat<S::nu, 2 * S::nq> K;
  K << -Kp, -Kd;
  return K;
}

/// The LQR weights of J = z(T)' Q_final z(T) + int z' Q z + w' R w dt (w = K z the feedback).
template <Scene S>
struct LqrWeights {
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  Mat<nx, nx> Q = Mat<nx, nx>::Identity();        ///< symmetric positive semidefinite
  Mat<nu, nu> R = Mat<nu, nu>::Identity();        ///< symmetric positive definite
  Mat<nx, nx> Q_final = Mat<nx, nx>::Identity();  ///< symmetric positive semidefinite
};

struct LqrOptions {
  double sample_step = 1e-3;  ///< s: the gain schedule's sample spacing (and every segment's ends)
  detail::OdeTolerances riccati{1e-10, 1e-12, 1e-4, 10'000'000};  ///< the backward Riccati integration
  int jump_iterations = 50;          ///< fixed-point iterations of the cost-to-go jump when G_v != 0
  double jump_tolerance = 1e-12;     ///< relative change that ends them
};

/// The time-varying LQR design along a reference with jumps (lqr_design).
template <Scene S>
struct LqrDesign {
  static constexpr int nx = 2 * S::nq;
  GainSchedule<S> gains;
  std::vector<Mat<nx, nx>> P_begin, P_end;  ///< cost-to-go at each segment's start and end (nominal)
  /// Per event: the conewise piece used for the cost-to-go jump (the worst, below), -1 for a linear gain.
  std::vector<int> worst_piece;
  std::vector<int> jump_iterations;  ///< per event: fixed-point iterations used (1 when G_v = 0)
  double seconds = 0.0;
};

/// Time-varying LQR along the reference of `open_loop` (which must linearise it with
/// FeedbackTreatment::Signal: the controller replaces the reference's law). Between events the
/// Riccati equation
///     -P' = A'P + P A - P B R^-1 B' P + Q,   K = -R^-1 B' P,
/// runs backwards from P(T) = Q_final; at event i the cost-to-go jumps through the closed-loop
/// jump gain J = G_z + G_v K_i(t*) (CL above): P_i(t*) = J' P_{i+1}(t*) J. Where G_v != 0 (a guard
/// that depends on the input), K_i(t*) depends on P_i(t*) itself: a fixed point, iterated. At a
/// simultaneous event the worst piece is used: the one with the largest lambda_max(J_p' P J_p)
/// (pieces whose outcome is not the nominal one have no segment after them and are left out). The
/// gains are sampled every options.sample_step and interpolated linearly (GainSchedule); the
/// closed-loop analysis uses the same schedule, so it analyses exactly the controller that runs.
/// @throws InvalidArgument (R not SPD, Q or Q_final not symmetric PSD, a LinearisedSystem with
/// FeedbackTreatment::ClosedLoop), NumericalFailure (the Riccati integration or the jump's fixed
/// point fails), whatever the conewise gains throw.
template <Scene S>
LqrDesign<S> lqr_design(const LinearisedSystem<S>& open_loop, const LqrWeights<S>& weights, const LqrOptions& options = {});

/// The reference-spreading tracking controller (RS) as a segmented input law (file comment).
/// Shares the extended reference of a LinearisedSystem (which must outlive it) and owns its gains.
/// Thread-safe: law() hands out independent laws, one per simulation.
template <Scene S>
class ReferenceSpreadingController {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = Vec<nx>;
  using Input = Vec<nu>;

  /// @throws InvalidArgument if the schedule's segment count is not the reference's.
  ReferenceSpreadingController(const ExtendedReference<S>& reference, GainSchedule<S> gains);
  ReferenceSpreadingController(ExtendedReference<S>&&, GainSchedule<S>) = delete;  // would dangle

  const ExtendedReference<S>& reference() const { return reference_; }
  const GainSchedule<S>& gains() const { return gains_; }
  /// The schedule's sample times of every segment and the reference's input breakpoints
  /// (HybridTrajectory::input_breakpoints), sorted and without repeats: the law's kinks and jumps
  /// in t (linear interpolation of K; u_i(t) piecewise constant). Give them to
  /// SimulationOptions::breakpoints so that no step of the plant's integration straddles one (a
  /// kink inside a step makes the error control cut the step down; measured on the hopper's LQR at
  /// 1 ms samples: 2.8 s per run without, see tracking.hpp; a jump inside a step that releases a
  /// contact is found as a guard crossing a round-off before the jump instead of the fixed-time
  /// event it is, Event::input_jump). monte_carlo() adds them itself.
  std::vector<double> breakpoints() const;

  /// u = u_i(t) + K_i(t) (x - x_i(t)) on reference segment i (no phase logic); x_i and u_i are
  /// held at the ends of the extended interval beyond them (file comment).
  /// @throws InvalidArgument (i out of range)
  Input input(int i, double t, const State& x) const;

  /// A fresh law for one simulation (it keeps the plant's event history, so one law per run):
  /// it maps the plant's segment (events seen) and mode to the reference segment or to the
  /// intermediate phase of a simultaneous event (file comment). @throws (when called)
  /// UnplannedEvent.
  SegmentedInputLaw<S> law() const;

  /// Where a plant segment stands with respect to the reference.
  struct Phase {
    int segment = 0;            ///< reference segment compared with (the ante-event one in the intermediate phase)
    bool intermediate = false;  ///< between the micro-events of a simultaneous reference event
    /// After a micro-event of the plant (a friction transition or a bounce) ahead of the reference
    /// event that ends `segment` and opens or closes a contact (file comment): u_i(t) alone until
    /// the post-event mode.
    bool micro_event_ahead = false;
  };
  /// The phase after a plant event from `mode_before` (the mode of the plant segment the event
  /// ends) into `mode`, given the phase before it (file comment). @throws UnplannedEvent
  Phase next_phase(const Phase& before, const Mode<nc>& mode_before, const Mode<nc>& mode) const;

 private:
  const ExtendedReference<S>& reference_;
  GainSchedule<S> gains_;
  std::vector<bool> simultaneous_;  ///< per reference event: fired by several guards at once
};

/// The closed-loop linearisation (CL) of a reference-spreading controller along its reference.
/// Not thread-safe (it builds conewise pieces on demand through the LinearisedSystem).
template <Scene S>
class ClosedLoopLinearisation {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = Vec<nx>;
  using Matrix = Mat<nx, nx>;

  /// `open_loop` must linearise the reference with FeedbackTreatment::Signal and outlive this
  /// object. `tolerances`: of the closed-loop variational integrations (default: the open
  /// loop's, LinearisationOptions::variational); the segments' transition matrices are computed
  /// on first use. @throws InvalidArgument (ClosedLoop treatment, a schedule of another length)
  ClosedLoopLinearisation(const LinearisedSystem<S>& open_loop, GainSchedule<S> gains,
                          std::optional<detail::OdeTolerances> tolerances = std::nullopt);
  ClosedLoopLinearisation(LinearisedSystem<S>&&, GainSchedule<S>,
                          std::optional<detail::OdeTolerances> = std::nullopt) = delete;  // would dangle

  const LinearisedSystem<S>& open_loop() const { return open_loop_; }
  const GainSchedule<S>& gains() const { return gains_; }
  int segment_count() const { return open_loop_.segment_count(); }

  /// A_i + B_i K_i at t on extended segment i.
  Matrix closed_loop_matrix(int i, double t) const;
  /// The closed-loop transition matrix on extended segment i from t0 to t1 (either order).
  Matrix flow_transition(int i, double t1, double t0) const;
  /// The closed-loop transition over segment i's nominal interval (computed on first use).
  /// @throws NumericalFailure (integration)
  const Matrix& segment_transition(int i) const;
  const detail::OdeTolerances& tolerances() const { return tolerances_; }
  /// Whether event i is simultaneous (conewise).
  bool conewise(int i) const { return open_loop_.conewise(i); }
  /// G_z + G_v K_i(t*) of event i. @throws SimultaneousActivation for a conewise event.
  Matrix jump(int i) const;
  /// The closed-loop pieces G_z + G_v K of conewise event i whose outcome is nominal (all built).
  std::vector<Matrix> jump_pieces(int i) const;
  /// The pieces of event i whose outcome is not nominal (no segment after them): they are left
  /// out of the bounds, and reported.
  int off_nominal_pieces(int i) const;
  /// The closed-loop jump of event i applied to z- (the piece of its cone at a conewise event).
  /// @throws SimultaneousActivation if z- lies in the cone of a piece whose outcome is not nominal.
  State apply_jump(int i, const State& z_minus) const;

  /// z(t) of the first-order closed loop from z(t0) = z0, t0 the reference's start, t on the
  /// nominal segment containing it (after the event at an event time). Conewise events apply the
  /// piece of their cone: positively homogeneous in z0.
  State propagate(const State& z0, double t) const;

 private:
  const LinearisedSystem<S>& open_loop_;
  GainSchedule<S> gains_;
  detail::OdeTolerances tolerances_;
  mutable std::vector<std::optional<Matrix>> segment_transition_;
};

/// Options of the stability checks.
template <Scene S>
struct StabilityOptions {
  static constexpr int nx = 2 * S::nq;
  Mat<nx, nx> weight = Mat<nx, nx>::Identity();  ///< W (SPD): |z|_W = sqrt(z' W z), of the deviation at t0
  /// W_out (symmetric PSD) of the deviation at t: a(t) = |z(t)|_Wout / |z(t0)|_W; by default W. A
  /// semi-norm measures what the design regulates (e.g. a hopper's joints: the body's momentum
  /// in flight is beyond any controller). The periodic check uses W on both sides (a norm).
  std::optional<Mat<nx, nx>> output_weight;
  /// The initial deviations considered: range(E) (E nx x r, full column rank r); none: all of
  /// R^nx. E.g. the box's coordinates of the plank-box (the plank starts at rest), or the
  /// deviations that keep a closed contact closed. a(t) is then the induced norm on range(E).
  std::optional<Eigen::Matrix<double, nx, Eigen::Dynamic, 0, nx, nx>> initial_subspace;
  int samples_per_segment = 20;  ///< times per segment where the peak amplification is sampled
  int random_directions = 200;   ///< random candidate deviations for the lower bound (seeded)
  std::uint64_t seed = 20261130;
  /// Piece sequences enumerated at most; beyond, the upper bound multiplies per-event maxima
  /// (sub-multiplicative, looser) and says so (exhaustive = false).
  long max_sequences = 4096;
  int jsr_depth = 4;  ///< periodic: products of length 1..jsr_depth for the JSR bounds
};

enum class StabilityVerdict { Stable, Unstable, Undecided };
const char* to_string(StabilityVerdict v);

/// The verdict of check_stability along a finite reference (file comment).
struct StabilityReport {
  StabilityVerdict verdict = StabilityVerdict::Undecided;
  double t0 = 0.0, t_final = 0.0;
  double upper_bound = 0.0;  ///< of a(T) = |z(T)|_Wout / |z(t0)|_W over first-order deviations (Wout = W unless output_weight is set)
  double lower_bound = 0.0;  ///< realised by the conewise map (equal to upper without simultaneous events)
  double upper_rate = 0.0, lower_rate = 0.0;  ///< log(bound) / (T - t0), 1/s
  double peak_upper = 0.0, peak_lower = 0.0;  ///< sup over the sampled t of a(t): bounds
  double peak_time = 0.0;                     ///< s, where the upper peak is
  double tail_amplification = 0.0;  ///< |Phi(T, t_last)|_W after the last event (bound: max over pieces reaching it)
  double tail_rate = 0.0;           ///< log(tail_amplification) / (T - t_last), 1/s
  long sequences = 1;               ///< piece sequences enumerated
  bool exhaustive = true;           ///< false: sub-multiplicative bound (too many sequences)
  int off_nominal_pieces = 0;       ///< pieces left out (outcome not nominal)
  double seconds = 0.0;
};

/// The stability check along the finite reference, from its start to t_final (default: its end).
/// @throws InvalidArgument (W not SPD, t_final outside the reference), NumericalFailure
template <Scene S>
StabilityReport check_stability(const ClosedLoopLinearisation<S>& closed_loop, const StabilityOptions<S>& options = {},
                                double t_final = -1.0);

/// The verdict of check_periodic_stability (file comment).
struct PeriodicStabilityReport {
  StabilityVerdict verdict = StabilityVerdict::Undecided;
  double period = 0.0;
  double spectral_radius_upper = 0.0;  ///< JSR upper bound (rho(M) without simultaneous events)
  double spectral_radius_lower = 0.0;  ///< a repeating sequence's rho (rho(M) without simultaneous events)
  int jsr_depth = 0;                   ///< the product length that gave the upper bound
  long sequences = 1;                  ///< piece sequences of one period
  std::vector<double> eigenvalue_moduli;  ///< of M (linear case), descending
  double seconds = 0.0;
};

/// Stability of a periodic reference: the closed-loop monodromy over [t0, t0 + period] (t0 the
/// reference's start; the reference must repeat with that period: state, mode and input, which is
/// checked on the state at t0 + period to `periodicity_tolerance`, relative).
/// @throws InvalidArgument (not periodic within the tolerance, period beyond the reference)
template <Scene S>
PeriodicStabilityReport check_periodic_stability(const ClosedLoopLinearisation<S>& closed_loop, double period,
                                                 const StabilityOptions<S>& options = {},
                                                 double periodicity_tolerance = 1e-6);

/// Monte Carlo validation of a design (file comment).
template <Scene S>
struct MonteCarloOptions {
  static constexpr int nx = 2 * S::nq;
  int runs = 200;
  double size = 1e-4;                      ///< eps: x(t0) + eps d
  Vec<nx> scale = Vec<nx>::Ones();          ///< d_j ~ N(0, scale_j^2) (zero scale: that coordinate is not perturbed)
  /// Applied to every drawn d before use (e.g. to keep a contact closed: zero the gap's row and
  /// project the velocity onto the constraint); null: d as drawn.
  std::function<Vec<nx>(const Vec<nx>&)> project;
  /// true: every perturbed start x(t0) + eps d (after `project`) is projected onto the contacts
  /// closed in the reference's first segment (ConstraintProjection: their gaps, normal velocities
  /// and sticking tangential velocities to zero, by the smallest change in the kinetic metric), so
  /// that the plant starts in the reference's first mode. A `project` that keeps a curved contact
  /// closed does so to first order only and leaves a gap of order eps^2 (about 1e-7 m on the
  /// hopper's stance at eps = 1e-4): the plant starts in flight and lands microseconds later. The
  /// change of the start is O(eps^2) for such a d; the prediction and |eps d|_W use the projected
  /// start's deviation (start - x(t0)) / eps.
  bool keep_initial_contacts = false;
  Mat<nx, nx> weight = Mat<nx, nx>::Identity();  ///< W (SPD) of the initial deviation |eps d|_W
  std::optional<Mat<nx, nx>> output_weight;       ///< W_out (PSD) of the final error; by default W
  std::uint64_t seed = 20261130;
  int threads = 0;      ///< 0: std::thread::hardware_concurrency()
  int batch = 50;       ///< runs per progress line
  std::ostream* progress = nullptr;  ///< one line per batch; null: silent
  double t_final = -1.0;  ///< default: the reference's end
  /// Times [s], increasing, in (t0, t_final], at which every run records its deviation and its
  /// first-order prediction (MonteCarloRun::observed_over_time, predicted_over_time): the
  /// deviations over time that a report draws against the prediction. Empty: none.
  std::vector<double> deviation_times;
  /// true: every run is measured against the nominal run (d = 0: the same plant, controller and
  /// simulator from x(t0)), the deviation being e(t) - e_0(t) with e = x - x_j the error against
  /// the reference segment of the run's own phase (extended by reference spreading) and e_0 the
  /// nominal run's. This is the finite difference of the closed-loop map that the first order
  /// predicts, and it cancels the reference's own defect: a collocation reference differs from the
  /// simulator's trajectory by its discretisation error, which the events' saltation matrices
  /// amplify (on the hopper over three holes refined to local error 2e-7, the nominal run is 1.7e-5
  /// off the reference before a touchdown of saltation norm 5.3e4, 0.6 after it); that defect is
  /// reported instead (MonteCarloReport::nominal_run_deviation). The nominal run is one simulation
  /// more, not counted in `runs`; it never throws out of monte_carlo: when it fails or leaves the
  /// event sequence, the runs are measured against the reference and nominal_run_departure says
  /// why. false: against the reference (e(t) alone), no nominal run.
  bool relative_to_nominal_run = true;
};

struct MonteCarloRun {
  bool failed = false;
  std::string reason;     ///< the exception's message (failed runs)
  /// Ends in the reference's last segment and mode with no unplanned event. A bounce ahead of a
  /// reference touchdown (a touchdown that leaves the contact open, which the controller takes as a
  /// micro-event: file comment) is a departure, "a bounce: the plant's touchdown into ... ahead of
  /// the event that ends reference segment j (t = ... s)": the first order has one touchdown there,
  /// the plant a touchdown, a lift-off and another touchdown.
  bool kept_event_sequence = false;
  /// A run that completed without keeping the event sequence: where it left it, e.g. "the plant's
  /// event into contact 0 slip+ where reference segment 12 has contact 0 stick (t = 2.2011 s)" or
  /// "ended in reference segment 11 of 0 .. 12"; empty otherwise.
  std::string departure;
  int events = 0;         ///< plant events (micro-events counted one by one)
  /// |x(T) - x_j(T)|_Wout / |eps d|_W, with x(T) - x_j(T) less the nominal run's x_0(T) - x_j(T)
  /// when MonteCarloReport::relative_to_nominal_run
  double observed = 0.0;
  double predicted = 0.0; ///< |z(T)|_Wout / |d|_W of the first-order closed loop
  /// At MonteCarloOptions::deviation_times t_k: |x(t_k) - x_j(t_k)|_Wout / |eps d|_W (less the
  /// nominal run's error at t_k as for `observed`), the plant
  /// compared with the reference segment of its own phase at t_k (extended by reference
  /// spreading), and |z(t_k)|_Wout / |d|_W. NaN where t_k lies beyond the extension of that
  /// segment, or where the prediction leaves the conewise pieces with a nominal outcome
  /// (SimultaneousActivation); observed_over_time is empty for a failed run, both are empty
  /// without deviation_times.
  std::vector<double> observed_over_time, predicted_over_time;
};

struct MonteCarloReport {
  int runs = 0, failed = 0, kept_event_sequence = 0;
  std::vector<MonteCarloRun> run;
  /// Why the failed runs failed, distinct up to the time they name ("at t = ..."), each with its
  /// count and the range of its times in the text ("65 x ... at t = 2.0020677 .. 2.0020681 ...")
  std::vector<std::string> failure_reasons;
  /// The departures of the completed runs that did not keep the event sequence, distinct up to the
  /// time, each with its count and the range of its times in the text
  std::vector<std::string> departures;
  /// max over kept runs of log(observed) / (T - t0); this, the median and max_log_discrepancy are
  /// NaN when no run kept the event sequence
  double observed_rate_max = 0.0;
  double observed_rate_median = 0.0;
  double predicted_rate_max = 0.0;  ///< the same of the first-order amplifications of the same d
  /// max over kept runs of |log(observed / predicted)|: the first-order regime when small
  double max_log_discrepancy = 0.0;
  int grew = 0, shrank = 0;  ///< kept runs with observed > 1 and < 1
  /// Whether the runs were measured against the nominal run (MonteCarloOptions::relative_to_nominal_run
  /// and the nominal run kept the event sequence) or against the reference.
  bool relative_to_nominal_run = false;
  /// The nominal run's |x_0(T) - x_j(T)|_Wout, and the largest of it at T and at the deviation times
  /// (equal without deviation_times), in the output weight's norm of the state (not divided by
  /// eps): the reference's defect as the closed loop sees it (for an exact reference, of the order
  /// of the simulator's tolerance). NaN when not asked for or when the nominal run failed; finite
  /// also when it left the event sequence.
  double nominal_run_deviation = std::numeric_limits<double>::quiet_NaN();
  double nominal_run_max_deviation = std::numeric_limits<double>::quiet_NaN();
  /// Empty when the nominal run kept the event sequence (or was not asked for); else why the runs
  /// were measured against the reference: "the nominal run failed: <reason>" or "the nominal run
  /// left the event sequence: <departure>".
  std::string nominal_run_departure;
  double seconds = 0.0;      ///< wall time of the simulations
  int threads = 1;
  std::vector<double> deviation_times;  ///< MonteCarloOptions::deviation_times [s]
};

/// Fills the statistics of `report` (runs, failed, kept_event_sequence, failure_reasons and
/// departures with their counts, the rates over `horizon` = T - t0 [s], the median, the largest log discrepancy, grew,
/// shrank) from report.run; what monte_carlo reports, also for a batch joined from chunks.
void summarise_monte_carlo(MonteCarloReport& report, double horizon);

/// Runs options.runs closed-loop simulations of `controller` from the reference's x(t0) + eps d
/// (scene and simulation options those of the reference), in parallel, and compares each with the
/// first-order prediction of `closed_loop` for the same d. A run that throws is recorded with its
/// reason, never rethrown. @throws InvalidArgument (runs < 1, size <= 0)
template <Scene S>
MonteCarloReport monte_carlo(const S& scene, const SimulationOptions& simulation,
                             const ReferenceSpreadingController<S>& controller,
                             const ClosedLoopLinearisation<S>& closed_loop, const MonteCarloOptions<S>& options = {});

namespace detail {
/// Runs body(index, worker) for index = 0..count-1 on `threads` workers (worker in 0..threads-1),
/// after_batch(done) whenever a multiple of `batch` indices (and the last) have completed, from
/// the finishing worker under a lock. Rethrows the first exception a body threw after joining.
void parallel_for(int count, int threads, int batch, const std::function<void(int, int)>& body,
                  const std::function<void(int)>& after_batch);
}  // namespace detail

}  // namespace saltus
