// First-order jump gains of the events of a hybrid trajectory (thesis appendix C, C.29-C.42):
//     z+ = G_z z- + G_v v-,
// z- the state deviation from the (extended) ante-event reference at the nominal event time t*,
// v- the input deviation there, z+ the deviation from the (extended) post-event reference at t*
// (reference spreading: both are compared with the segment that has seen the same jumps).
//
// Derivation (written out again because the draft thesis carries typos, see below). A perturbed
// motion x_eps = alpha- + eps z- (+ o(eps)) under u_eps = mu + eps v reaches the guard at
// t_eps = t* + eps dt. Expanding gamma(x_eps(t_eps), u_eps(t_eps), t_eps) = 0 to first order
// (C.17-C.21):
//     Dgamma_x (z- + f- dt) + Dgamma_u (v + mu'- dt) + d_t gamma dt = 0
//  => dt = -(Dgamma_x z- + Dgamma_u v) / gamma_dot,                                   (C.22)
//     gamma_dot = Dgamma_x f- + Dgamma_u mu'- + d_t gamma,                            (C.24)
// with f- the ante-event flow at (alpha-(t*), mu-(t*)) and mu'- the total time derivative of the
// ante-event input law along the extended ante-event flow. Saltus' guards do not depend on t
// explicitly (guards.hpp), so d_t gamma = 0; time enters through the input law only.
// At t_eps the jump x+ = g(x-) is applied (g does not depend on u: impulses are not inputs), and
// the post-event reference at t_eps is alpha+(t*) + eps f+ dt, so
//     z+ = Dg (z- + f- dt) - f+ dt = Dg z- + (f+ - Dg f-) (Dgamma_x z- + Dgamma_u v) / gamma_dot,
// where f+ is the post-event flow at (alpha+(t*), mu+(t*)) (the post-event mode's input). Hence
//     G_z = Dg + (f+ - Dg f-) Dgamma_x / gamma_dot,                                   (C.37)
//     G_v =      (f+ - Dg f-) Dgamma_u / gamma_dot.                                   (C.38)
// Typos of the draft corrected here: C.38 adds D_2 g, which is zero (the thesis says so itself
// under C.27); C.35 writes gdot with D_2 g mu' and D_3 g, both zero for Saltus' jump maps; C.41
// writes G_z^{k+} v^k for G_v^{k+} v^k (C.42 has it right); C.51 uses f^{k-} where C.52 has
// f^{k+} for the intermediate mode's flow f^k.
//
// Note on the state-input guards. At a release lambda_n = 0 (and a slipping contact's friction
// mu lambda_n with it), and at a slip onset the stick force sits on the cone, equal to the slip
// force: the contact forces are continuous, so with an input law that does not depend on the
// mode f+ = f- and G_z = Dg = I, G_v = 0, whatever gamma_dot is. The saltation term, and with it
// the input rate in gamma_dot, matters when the input changes with the mode (a flight torque
// different from the stance torque: f+ - f- = (0, M^{-1} S (u+ - u-))).
//
// Chains at one instant (an impact into stick that slips at once, a release at the instant of
// another event) are composed transition by transition (C.40-C.42) with the intermediate modes'
// flows, keeping the first-order event-time shift dt_k of every transition:
//     z_k = Dg_k (z_{k-1} + f_{k-1} dt_k) - f_k dt_k,
// where f_{k-1}, f_k are the flows of the modes before and after transition k at its state.
//  - A transition whose guard sits at zero (within the chain tolerance) and decreases has its own
//    shift dt_k = -(Dgamma_x z_{k-1} + Dgamma_u v) / gamma_dot_k, with gamma_dot_k along the
//    intermediate mode's flow f_{k-1}: the intermediate mode lasts eps (dt_k - dt_{k-1}) in the
//    perturbed motion. This is C.40-C.42; it is the gain of the cone dt_k >= dt_{k-1}. The other
//    order belongs to the conewise gains of simultaneous events, not computed here.
//  - A transition whose guard is already clearly negative when the previous one ends (the
//    intermediate mode has zero duration for every nearby motion too: e.g. an impact into stick
//    where the stick forces leave the friction cone) happens at the same perturbed instant as the
//    previous one: dt_k = dt_{k-1}. Then the flow of the zero-duration mode cancels out, and for a
//    mode change without impulse (Dg_k = I) the composite gain is exactly that of one jump from
//    the first mode to the last. Using C.37 with gamma_dot_k there would be wrong (the guard does
//    not cross zero, it is below it).
// An event without guards (the initial impact at t0 of a simulation started in contact) has a
// fixed time: dt = 0, G_z = Dg, G_v = 0. So does an event fired by an input jump
// (Event::input_jump): a release where a piecewise-constant input jumps at a breakpoint so that
// the contact would pull under the input after it (the simulator fires it there, Simulator::run).
// The guard does not cross zero, it jumps below it with the input, and nearby motions release at
// the same instant while the force before the jump stays positive: dt = 0 (C.22 does not apply;
// its gamma_dot would divide a value that is not a crossing's). An event located by its crossing
// a round-off before a jump is a crossing, as before.
//
// Coincident guards. A transition fired by several guards at once is conewise in general
// (conewise_gain.hpp). When the guards' first-order crossing-time shifts are the same linear
// function of (z-, v) (relative difference <= coincidence_tolerance), no perturbation separates
// them: they fire together in every nearby motion and the gain is linear, computed with the first
// guard. Redundant contacts do this: both bottom corners of a box sliding flat on the ground have
// the same tangential velocity x' + b theta' whatever the state, so their stop guards coincide and
// a flat box sliding to a stop has an ordinary jump gain.
//
// Feedback. When the input law depends on the state, u = kappa(t, x, mode) (a tracking
// controller), a state deviation z- also moves the input by K z-, K = d kappa / dx at
// (t*, alpha-(t*), mode-), and the guard sees it: in C.22 Dgamma_x becomes the closed-loop
// gradient Dgamma_x + Dgamma_u K (FeedbackTreatment::ClosedLoop, the default). gamma_dot is
// unchanged: mu'- is already the total derivative of kappa along the ante-event flow. The flows
// f-, f+ are those of the closed loop (the law evaluated at the event state). With
// FeedbackTreatment::Signal the input is treated as the signal mu(t) = kappa(t, alpha(t), mode)
// fixed along the reference: right for open-loop laws (K = 0 then anyway), and for a feedback law
// only if the perturbed system is driven by that signal and not by the law.
// K is a central difference of the law in x (feedback_gain below): the law is a user's function
// on doubles, not a templated one, so automatic differentiation cannot reach it. For an affine
// law (PD tracking) the difference is exact up to round-off, O(eps |u| / h); otherwise O(h^2).
#pragma once

#include <saltus/hybrid/dynamics/derivatives.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace saltus {

/// A guard crossing that is (nearly) tangential: |gamma_dot| <= threshold * rate scale, where the
/// rate scale is |Dgamma_x| |f-| + |Dgamma_u| |mu'-|. The first-order gain would be huge or
/// undefined (the event time is not differentiable), so none is returned.
class GrazingEvent : public Error {
 public:
  GrazingEvent(const std::string& what, double t, Guard guard, double gamma_dot, double rate_scale)
      : Error(what), t_(t), guard_(guard), gamma_dot_(gamma_dot), rate_scale_(rate_scale) {}
  double t() const { return t_; }
  const Guard& guard() const { return guard_; }
  double gamma_dot() const { return gamma_dot_; }
  double rate_scale() const { return rate_scale_; }

 private:
  double t_;
  Guard guard_;
  double gamma_dot_, rate_scale_;
};

/// A transition fired by several guards at once whose crossings a perturbation separates (e.g.
/// both corners of a box landing flat): its first-order gain is conewise linear (one gain per
/// activation order: ConewiseJumpGain), not computed by JumpGainSolver.
class SimultaneousActivation : public Error {
 public:
  using Error::Error;
};

/// How the input law's dependence on the state enters the gains and the linearisation.
enum class FeedbackTreatment {
  ClosedLoop,  ///< u = kappa(t, x, mode) acts on the perturbed state: d kappa / dx is included
  Signal       ///< u is the signal kappa(t, x_ref(t), mode) of the reference: d kappa / dx left out
};

struct JumpGainOptions {
  FeedbackTreatment feedback = FeedbackTreatment::ClosedLoop;
  /// Central-difference step of d kappa / dx, relative to max(1, |x_j|).
  double feedback_step = 1e-6;
  /// GrazingEvent when |gamma_dot| <= grazing_threshold * (|Dgamma_x| |f-| + |Dgamma_u| |mu'-|).
  double grazing_threshold = 1e-8;
  /// Include Dgamma_u mu'- in gamma_dot (C.24). Only to show that it is needed (tests).
  bool include_input_rate = true;
  /// s, relative to max(1, |t|): central-difference step of the input law's total time
  /// derivative along the ante-event flow, (u(t + h, x + h f) - u(t - h, x - h f)) / 2h,
  /// Richardson-extrapolated with h/2. Its error is O(h^4 u^(5)) + O(eps |u| / h). The input
  /// law must be smooth within +-h of the event (no breakpoint there).
  double input_rate_step = 1e-5;
  /// s: a chained transition whose guard is below -chain_time_tolerance * (rate scale) when the
  /// previous transition ends is immediate (dt_k = dt_{k-1}); otherwise it is at zero and crosses.
  double chain_time_tolerance = 1e-8;
  /// Guards of one transition whose first-order crossing-time shifts differ by at most this
  /// (relative) coincide: the gain is linear (see "Coincident guards"), else SimultaneousActivation.
  double coincidence_tolerance = 1e-10;
  /// The differentiated jump map must reproduce the impact solver's post-impact state:
  /// max |g(x-) - x+| <= this * max(1, |x+|), else ContactProblemFailure (the derivative would be
  /// that of another jump). Seen where four coplanar corners of the spatial box slip through one
  /// impact (residual 1.4e-5-3.3e-5: redundant contacts whose split of the normal impulse, and
  /// with it of the friction impulse, the two settle differently).
  double jump_map_tolerance = 1e-9;
};

/// K = d kappa / dx of an input law at (t, x, mode) by central differences with steps
/// h_j = step * max(1, |x_j|); `probe` is scratch. Exactly zero for a law that ignores x.
template <Scene S>
void feedback_gain(const InputLaw<S>& law, double t, const Vec<2 * S::nq>& x, const Mode<S::nc>& mode, double step,
                   Vec<2 * S::nq>& probe, Mat<S::nu, 2 * S::nq>& K);

/// What is known about one transition of an event (diagnostics, and for the tests).
struct TransitionGainInfo {
  bool guarded = false;    ///< fired by a guard (false: initial impact)
  bool immediate = false;  ///< its guard was already below zero: same instant as the previous one
  double gamma = 0.0;      ///< guard value at the transition's state
  double gamma_dot = 0.0;  ///< C.24 along the flow of the mode before
  double rate_scale = 0.0;
};

/// The first-order crossing of one guard at a state of a mode (C.22-C.24): the shift of its
/// crossing time is dt = -(dgamma_x z + dgamma_u v) / gamma_dot for a state deviation z from the
/// mode's extended flow through x and an input deviation v.
template <Scene S>
struct GuardCrossing {
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  double gamma = 0.0;       ///< the guard's value at x
  double gamma_dot = 0.0;   ///< C.24 along the mode's flow, the input rate included
  double state_rate = 0.0;  ///< dgamma_x f (open loop)
  double input_rate = 0.0;  ///< dgamma_u mu'
  double rate_scale = 0.0;  ///< |dgamma_x| |f| + |dgamma_u| |mu'|: grazing when |gamma_dot| is small against it
  /// dgamma_x, closed loop (dgamma_x + dgamma_u K) with FeedbackTreatment::ClosedLoop, and dgamma_u.
  Eigen::Matrix<double, 1, nx> dgamma_x = Eigen::Matrix<double, 1, nx>::Zero();
  Eigen::Matrix<double, 1, nu> dgamma_u = Eigen::Matrix<double, 1, nu>::Zero();
};

/// The gain of one event: z+ = G_z z- + G_v v-, and the first-order shift of its (first) event
/// time, dt = dt_dz z- + dt_dv v-.
template <Scene S>
struct JumpGain {
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  Mat<nx, nx> G_z = Mat<nx, nx>::Identity();
  Mat<nx, nu> G_v = Mat<nx, nu>::Zero();
  Eigen::Matrix<double, 1, nx> dt_dz = Eigen::Matrix<double, 1, nx>::Zero();
  Eigen::Matrix<double, 1, nu> dt_dv = Eigen::Matrix<double, 1, nu>::Zero();
  Vec<nx> f_minus = Vec<nx>::Zero(), f_plus = Vec<nx>::Zero();  ///< flows before and after the event
  /// max |g(x_before) - x_after| over the impact transitions: the jump map differentiated
  /// against the impact solver's post-impact state (round-off; above
  /// JumpGainOptions::jump_map_tolerance compute() throws).
  double jump_map_residual = 0.0;
  int transitions = 0;
  std::vector<TransitionGainInfo> info;  ///< one per transition (sized once per event)
};

/// Computes jump gains with preallocated workspaces; compute() allocates nothing for events with
/// at most `reserved_transitions` transitions (the user's input law may allocate).
template <Scene S>
class JumpGainSolver {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = Vec<nx>;
  using Input = Vec<nu>;

  explicit JumpGainSolver(const S& scene, JumpGainOptions options = {}, int reserved_transitions = 8);
  JumpGainSolver(S&&, JumpGainOptions = {}, int = 8) = delete;  // keeps a reference: would dangle

  const JumpGainOptions& options() const { return options_; }

  /// The gain of `event` under the input law that drove the trajectory.
  /// @throws GrazingEvent, SimultaneousActivation, InvalidArgument (an event without transitions),
  /// ContactProblemFailure (the differentiated jump map does not reproduce x+: jump_map_tolerance)
  const JumpGain<S>& compute(const Event<S>& event, const InputLaw<S>& law);
  /// The same for a deviation that reaches the event as z = incoming_z z0 + incoming_v v (nx x nx
  /// and nx x nu maps of an outer deviation z0, e.g. the micro-events before it in a conewise
  /// gain): everything comes out composed, in terms of (z0, v): with G^e the event's own gain,
  /// G_z = G_z^e incoming_z, G_v = G_z^e incoming_v + G_v^e, and dt_dz, dt_dv likewise; coincident
  /// guards are judged on the deviations the maps can reach.
  const JumpGain<S>& compute(const Event<S>& event, const InputLaw<S>& law, const Mat<nx, nx>& incoming_z,
                             const Mat<nx, nu>& incoming_v);

  /// The first-order crossing of `guard` at (t, x) in `mode` under `law` (the same quantities
  /// compute() uses for a guarded transition; the guard must be one of the mode's). No check of
  /// transversality: the caller compares |gamma_dot| with grazing_threshold * rate_scale. The
  /// reference is to the solver's own buffer: the next crossing() or compute() overwrites it.
  const GuardCrossing<S>& crossing(const InputLaw<S>& law, double t, const State& x, const Mode<nc>& mode,
                                   const Guard& guard);

 private:
  // True if the first-order crossing-time shifts of tr's guards coincide (given Zz_, Zv_ of the
  // transitions before); `mismatch` gets their largest relative difference.
  bool coincident_guards(const InputLaw<S>& law, double t, const Transition<S>& tr, double& mismatch);
  // The crossing of `guard` at (t, x) in `mode`, whose flow there is f (into crossing_).
  void evaluate_crossing(const InputLaw<S>& law, double t, const State& x, const Mode<nc>& mode, const Guard& guard,
                         const State& f);

  // (u(t + h, x + h f) - u(t - h, x - h f)) / 2h along the flow f_before_ of the mode before.
  void input_rate(const InputLaw<S>& law, double t, const State& x, const Mode<nc>& mode, double h, Input& out);

  const S& scene_;
  JumpGainOptions options_;
  std::unique_ptr<DerivativeWorkspace<S>> ws_;  // dual-number matrices: large, made once
  FlowWorkspace<S> flow_;
  JumpGain<S> gain_;
  GuardCrossing<S> crossing_;
  Mat<nx, nx> Zz_, A_, Dg_;
  Mat<nx, nu> Zv_, B_;
  Mat<nu, nx> K_;
  Eigen::Matrix<double, 1, nx> dz_, dgx_;
  Eigen::Matrix<double, 1, nu> dv_, dgu_;
  State f_before_, f_after_, x_probe_, x_jump_, jump_f_, f_crossing_;
  Input u_before_, u_after_, u_dot_, u_rate_half_;
};

/// The gains of every event of `traj`, in order, under the trajectory's own input law.
template <Scene S>
std::vector<JumpGain<S>> jump_gains(const S& scene, const HybridTrajectory<S>& traj, const JumpGainOptions& options = {});

}  // namespace saltus
