// The linearised time-triggered hybrid system along a reference (thesis appendix C; DESIGN.md,
// "Reference spreading", hybrid/reference/reference_spreading.hpp): on each extended segment i
//     z' = A_i(t) z + B_i(t) v(t),   A_i = df_i/dx, B_i = df_i/du at (x_i(t), u_i(t)),
// where x_i is segment i continued past its events with its own mode's flow and its own input
// u_i(t) = law(t, x_i(t), mode_i), and at the nominal event time t_i (the end of segment i)
//     z_{i+1}(t_i) = G_z^i z_i(t_i) + G_v^i v(t_i)                     (C.39, jump_gain.hpp).
// A perturbed motion x_eps(t) that has seen k jumps is approximated by x_k(t) + eps z_k(t), at any
// t of the extended segment k, also between the nominal and the perturbed event times.
//
// Inputs: the reference's input along extended segment i is u_i(t) = ExtendedReference::input(i, t)
// and the perturbed system is driven by law(t, x, mode) + v(t), as the Simulator integrates it.
// With FeedbackTreatment::ClosedLoop (options.gains.feedback, the default) the law's dependence
// on the state is linearised too: A_i = df/dx + df/du K_i(t), K_i = d law / dx at
// (t, x_i(t), mode_i) by central differences (feedback_gain, jump_gain.hpp); with
// InputExtension::Hold the extensions hold the input, so K_i = 0 outside the nominal interval.
// With FeedbackTreatment::Signal, A_i = df/dx: the input is the reference's signal u_i(t).
// For an open-loop law (u depends on t only) both are the same system.
//
// State-transition matrices come from the variational equations Phi' = A Phi integrated with the
// reference state itself (x' = f, so A is evaluated on the accurate state, not on an interpolant),
// by an adaptive Dormand-Prince loop on fixed-size Eigen matrices (detail/ode.hpp). A and B come
// from automatic differentiation of the flow (flow_jacobian, derivatives.hpp).
//
// Simultaneous events (a transition fired by several guards at once: a box landing flat) have a
// conewise-linear, positively homogeneous gain (conewise_gain.hpp): predict() applies the piece
// whose cone contains the propagated deviation (z-, v(t*)), so the prediction is positively
// homogeneous in (z0, v), not linear; gains()[i] of such an event is NaN (use conewise_gain(i)),
// and state_transition() across it throws SimultaneousActivation (there is no matrix). A piece
// whose post-event outcome differs from the nominal one (an order that leaves a contact open, or
// ends in another slip velocity) has no extended segment to continue on: predict() throws
// SimultaneousActivation naming the order.
//
// Not thread-safe: one LinearisedSystem owns one derivative workspace, and builds the pieces of
// conewise gains as predictions need them.
#pragma once

#include <saltus/hybrid/reference/reference_spreading.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/detail/ode.hpp>
#include <saltus/sensitivity/jump_gain.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace saltus {

struct LinearisationOptions {
  JumpGainOptions gains;
  /// Reference spreading: extension lengths (s), input extension and the extensions' tolerances.
  ExtensionOptions spreading;
  /// Tolerances of the variational integrations.
  detail::OdeTolerances variational;
  /// The event physics that composes the micro-events of simultaneous events (conewise gains):
  /// the reference's own simulation options.
  SimulationOptions simulation;
};

template <Scene S>
class LinearisedSystem;

/// The first-order prediction z of one perturbation (z(t0), v(t)): z(i, t) on extended segment i.
template <Scene S>
class Prediction {
 public:
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  using State = Vec<nx>;

  /// z on extended segment i at t (the deviation from extended segment i).
  State z(int i, double t) const { return system_->propagate(i, z_begin_[i], *v_, t); }
  /// z at the nominal segment containing t (after the event at an event time).
  State at(double t) const { return z(system_->reference().reference().segment_at(t), t); }
  /// z just after the start and just before the end of nominal segment i.
  const State& z_begin(int i) const { return z_begin_.at(i); }
  const State& z_end(int i) const { return z_end_.at(i); }

 private:
  friend class LinearisedSystem<S>;
  const LinearisedSystem<S>* system_ = nullptr;
  std::shared_ptr<const std::function<Vec<nu>(double)>> v_;
  std::vector<State> z_begin_, z_end_;
};

template <Scene S>
class LinearisedSystem {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = Vec<nx>;
  using Input = Vec<nu>;
  using InputPerturbation = std::function<Input(double)>;
  using Reference = ExtendedReference<S>;

  /// Extends the segments of `traj` and computes the gains of all its events. `traj` and `scene`
  /// must outlive this object. @throws GrazingEvent, SimultaneousActivation (from the gains), InvalidArgument
  LinearisedSystem(S&&, const HybridTrajectory<S>&, LinearisationOptions = {}) = delete;  // keeps the scene: would dangle
  /// Simultaneous events get a conewise gain (header comment); options.simulation must be the
  /// reference's simulation options for those. @throws GrazingEvent, InvalidArgument (from the
  /// gains and ConewiseJumpGain's constructor), SimultaneousActivation (a later transition of an
  /// event fired by several non-coincident guards).
  LinearisedSystem(const S& scene, const HybridTrajectory<S>& traj, LinearisationOptions options = {});

  const S& scene() const { return scene_; }
  const LinearisationOptions& options() const { return options_; }
  const Reference& reference() const { return reference_; }
  /// The gain of every event; for a simultaneous event (conewise(i)) G_z and G_v are NaN (the
  /// other fields are left at their defaults): use conewise_gain(i).
  const std::vector<JumpGain<S>>& gains() const { return gains_; }
  /// Event i is fired by several guards at once: its gain is conewise_gain(i).
  bool conewise(int i) const { return conewise_.at(i) != nullptr; }
  /// The conewise gain of simultaneous event i (mutable: it builds pieces on demand). @throws
  /// InvalidArgument if event i is not one.
  ConewiseJumpGain<S>& conewise_gain(int i) const;
  int segment_count() const { return reference_.segment_count(); }

  const Mode<nc>& mode(int i) const { return reference_.reference().segments.at(i).mode; }
  double t_begin(int i) const { return reference_.reference().segments.at(i).t_begin; }  ///< nominal
  double t_end(int i) const { return reference_.reference().segments.at(i).t_end; }      ///< nominal
  /// The state segment i starts from: x+ of the event before it, or the initial state.
  State begin_state(int i) const;

  /// A and B of segment i's mode at (t, x) with the segment's input u_i(t): A = df/dx + df/du K
  /// in closed loop (see the header), df/dx otherwise; B = df/du.
  void jacobians(int i, double t, const State& x, Mat<nx, nx>& A, Mat<nx, nu>& B) const;
  /// K_i(t) = d law / dx along extended segment i at (t, x): zero with FeedbackTreatment::Signal,
  /// and outside the nominal interval with InputExtension::Hold.
  Mat<nu, nx> feedback(int i, double t, const State& x) const;
  /// A, B on the extended reference of segment i at t.
  void jacobians(int i, double t, Mat<nx, nx>& A, Mat<nx, nu>& B) const { jacobians(i, t, reference_.state(i, t), A, B); }

  /// Phi_i(t1, t0) on extended segment i (t0, t1 in its extended interval, either order).
  Mat<nx, nx> transition_matrix(int i, double t1, double t0) const;

  /// The state-transition matrix of the time-triggered hybrid system from t0 to t1 >= t0 along
  /// the nominal segments, with the jump gains G_z at the nominal event times in between.
  Mat<nx, nx> state_transition(double t1, double t0) const;

  /// The first-order prediction of the motion from x(t0) + eps z0 under u + eps v(t), t0 the
  /// reference's start.
  Prediction<S> predict(const State& z0, InputPerturbation v) const;
  /// Same without an input perturbation (v = 0; the only one of a scene with nu = 0).
  Prediction<S> predict(const State& z0) const {
    return predict(z0, [](double) { return Input::Zero().eval(); });
  }

  /// z(t) on extended segment i from z(t_begin(i)) = z_begin under v.
  State propagate(int i, const State& z_begin, const InputPerturbation& v, double t) const;

 private:
  bool closed_loop_at(int i, double t) const;
  // A += B K_i(t) in closed loop (K by central differences of the law in x).
  void close_loop(int i, double t, const State& x, Mat<nx, nx>& A, const Mat<nx, nu>& B) const;

  // x on extended segment i at t0, integrated from the segment's start with the variational tolerances.
  State start_state(int i, double t0) const;

  const S& scene_;
  LinearisationOptions options_;
  Reference reference_;
  std::vector<JumpGain<S>> gains_;
  /// Per event: the conewise gain of a simultaneous event (pieces built on demand), else null.
  std::vector<std::unique_ptr<ConewiseJumpGain<S>>> conewise_;
  std::unique_ptr<DerivativeWorkspace<S>> ws_;
  mutable FlowWorkspace<S> flow_;
  mutable State probe_;
  mutable Mat<nu, nx> K_;
};

}  // namespace saltus
