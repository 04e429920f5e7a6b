// Definitions of linearisation.hpp (see there for the math).
#pragma once

#include <saltus/sensitivity/conewise_gain.hxx>
#include <saltus/sensitivity/detail/ode.hxx>
#include <saltus/sensitivity/linearisation.hpp>

#include <limits>

namespace saltus {

template <Scene S>
LinearisedSystem<S>::LinearisedSystem(const S& scene, const HybridTrajectory<S>& traj, LinearisationOptions options)
    : scene_(scene),
      options_(options),
      reference_(scene, traj, options.spreading),
      ws_(std::make_unique<DerivativeWorkspace<S>>()) {
  JumpGainSolver<S> solver(scene, options.gains);
  const std::size_t n = traj.events.size();
  gains_.resize(n);
  conewise_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Event<S>& ev = traj.events[i];
    if (!ev.transitions.empty() && ev.transitions.front().guards.size() > 1) {
      try {  // coincident guards: an ordinary linear gain (jump_gain.hpp, "Coincident guards")
        gains_[i] = solver.compute(ev, traj.input);
        continue;
      } catch (const SimultaneousActivation&) {
      }
      ConewiseGainOptions c;
      c.gains = options.gains;
      c.simulation = options.simulation;  // with the reference's input jumps (no step straddles one)
      c.simulation.breakpoints.insert(c.simulation.breakpoints.end(), traj.input_breakpoints.begin(),
                                      traj.input_breakpoints.end());
      conewise_[i] = std::make_unique<ConewiseJumpGain<S>>(scene, ev, traj.input, c);
      gains_[i].G_z.setConstant(std::numeric_limits<double>::quiet_NaN());
      gains_[i].G_v.setConstant(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    gains_[i] = solver.compute(ev, traj.input);
  }
}

template <Scene S>
ConewiseJumpGain<S>& LinearisedSystem<S>::conewise_gain(int i) const {
  SALTUS_REQUIRE(i >= 0 && i < static_cast<int>(conewise_.size()) && conewise_[i],
                 "conewise_gain: event ", i, " is not a simultaneous event");
  return *conewise_[i];
}

template <Scene S>
auto LinearisedSystem<S>::begin_state(int i) const -> State {
  const auto& traj = reference_.reference();
  return i > 0 ? traj.events.at(i - 1).x_plus : traj.state(0, t_begin(0));
}

template <Scene S>
void LinearisedSystem<S>::jacobians(int i, double t, const State& x, Mat<nx, nx>& A, Mat<nx, nu>& B) const {
  const Input u = reference_.input(i, t);
  State f;
  flow_jacobian(scene_, mode(i), x, u, *ws_, f, A, B);
  close_loop(i, t, x, A, B);
}

template <Scene S>
auto LinearisedSystem<S>::feedback(int i, double t, const State& x) const -> Mat<nu, nx> {
  Mat<nu, nx> K = Mat<nu, nx>::Zero();
  if (closed_loop_at(i, t)) {
    State probe;
    feedback_gain<S>(reference_.reference().input, t, x, mode(i), options_.gains.feedback_step, probe, K);
  }
  return K;
}

template <Scene S>
auto LinearisedSystem<S>::transition_matrix(int i, double t1, double t0) const -> Mat<nx, nx> {
  // [x, Phi] stacked column-wise in one vector (odeint's vector-space algebra wants vectors).
  using Aug = Eigen::Matrix<double, nx*(nx + 1), 1>;
  using AugMap = Eigen::Map<Eigen::Matrix<double, nx, nx + 1>>;
  using ConstAugMap = Eigen::Map<const Eigen::Matrix<double, nx, nx + 1>>;
  const State x0 = start_state(i, t0);
  Aug y;
  AugMap Y(y.data());
  Y.col(0) = x0;
  Y.template rightCols<nx>().setIdentity();
  Mat<nx, nx> A;
  Mat<nx, nu> B;
  State f;
  auto rhs = [&](double t, const Aug& a, Aug& dadt) {
    const ConstAugMap Av(a.data());
    AugMap D(dadt.data());
    const State x = Av.col(0);
    const Input u = reference_.input(i, t);
    flow_jacobian(scene_, mode(i), x, u, *ws_, f, A, B);
    close_loop(i, t, x, A, B);
    D.col(0) = f;
    D.template rightCols<nx>().noalias() = A * Av.template rightCols<nx>();
  };
  detail::integrate_adaptive(rhs, y, t0, t1, options_.variational);
  return Y.template rightCols<nx>();
}

template <Scene S>
auto LinearisedSystem<S>::state_transition(double t1, double t0) const -> Mat<nx, nx> {
  const auto& traj = reference_.reference();
  SALTUS_REQUIRE(t1 >= t0, "state_transition: t1 = ", t1, " < t0 = ", t0);
  int i = traj.segment_at(t0);
  const int last = traj.segment_at(t1);
  Mat<nx, nx> Phi = Mat<nx, nx>::Identity();
  double t = t0;
  for (; i < last; ++i) {
    if (conewise_[i])
      throw SimultaneousActivation(detail::concat(
          "state_transition: the event at t = ", t_end(i), " is simultaneous; its gain is conewise (positively "
          "homogeneous, not linear), so the transition map has no matrix: use predict()"));
    Phi = (gains_[i].G_z * transition_matrix(i, t_end(i), t) * Phi).eval();
    t = t_end(i);
  }
  return transition_matrix(last, t1, t) * Phi;
}

template <Scene S>
auto LinearisedSystem<S>::predict(const State& z0, InputPerturbation v) const -> Prediction<S> {
  SALTUS_REQUIRE(static_cast<bool>(v), "predict: the input perturbation is empty");
  Prediction<S> p;
  p.system_ = this;
  p.v_ = std::make_shared<const InputPerturbation>(std::move(v));
  const int n = segment_count();
  p.z_begin_.resize(n);
  p.z_end_.resize(n);
  State z = z0;
  for (int i = 0; i < n; ++i) {
    p.z_begin_[i] = z;
    z = propagate(i, z, *p.v_, t_end(i));
    p.z_end_[i] = z;
    if (i + 1 < n) {
      const double te = t_end(i);
      Input vi = Input::Zero();
      if constexpr (nu > 0) vi = (*p.v_)(te);
      if (conewise_[i]) {
        const ConewisePiece<S>& piece = conewise_[i]->piece(z, vi);
        if (!piece.nominal_outcome) {
          std::string order;
          for (const auto& group : piece.order)
            for (const Guard& g : group)
              order += detail::concat(order.empty() ? "" : ", ", to_string(g.kind), " of '", scene_.contact(g.contact).name, "'");
          throw SimultaneousActivation(detail::concat(
              "predict: at the simultaneous event at t = ", te, " the perturbation lies in the cone of the order [",
              order, "], whose post-event state or mode differs from the nominal one (", piece.never_crossed.size(),
              " guard(s) never crossed, post-state difference ", piece.post_state_difference,
              "): there is no reference segment to continue on"));
        }
        z = (piece.G_z * z).eval();
        if constexpr (nu > 0) z += piece.G_v * vi;
      } else {
        z = gains_[i].G_z * z;
        if constexpr (nu > 0) z += gains_[i].G_v * vi;
      }
    }
  }
  return p;
}

template <Scene S>
auto LinearisedSystem<S>::propagate(int i, const State& z_begin, const InputPerturbation& v, double t) const -> State {
  using Aug = Eigen::Matrix<double, 2 * nx, 1>;  // [x; z]
  const double t0 = t_begin(i);
  Aug y;
  y.template head<nx>() = begin_state(i);
  y.template tail<nx>() = z_begin;
  Mat<nx, nx> A;
  Mat<nx, nu> B;
  State f;
  auto rhs = [&](double s, const Aug& a, Aug& dadt) {
    const State x = a.template head<nx>();
    const Input u = reference_.input(i, s);
    flow_jacobian(scene_, mode(i), x, u, *ws_, f, A, B);
    close_loop(i, s, x, A, B);
    dadt.template head<nx>() = f;
    dadt.template tail<nx>().noalias() = A * a.template tail<nx>();
    if constexpr (nu > 0) dadt.template tail<nx>().noalias() += B * v(s);
  };
  detail::integrate_adaptive(rhs, y, t0, t, options_.variational);
  return y.template tail<nx>();
}

template <Scene S>
bool LinearisedSystem<S>::closed_loop_at(int i, double t) const {
  if constexpr (nu == 0) return false;
  if (options_.gains.feedback != FeedbackTreatment::ClosedLoop) return false;
  return options_.spreading.input == InputExtension::Evaluate || (t >= t_begin(i) && t <= t_end(i));
}

template <Scene S>
void LinearisedSystem<S>::close_loop(int i, double t, const State& x, Mat<nx, nx>& A, const Mat<nx, nu>& B) const {
  if constexpr (nu > 0) {  // (without inputs there is no loop to close, and no 12 x 0 products)
    if (!closed_loop_at(i, t)) return;
    feedback_gain<S>(reference_.reference().input, t, x, mode(i), options_.gains.feedback_step, probe_, K_);
    A.noalias() += B * K_;
  }
}

template <Scene S>
auto LinearisedSystem<S>::start_state(int i, double t0) const -> State {
  State x = begin_state(i);
  auto rhs = [&](double t, const State& y, State& dydt) {
    const Input u = reference_.input(i, t);
    evaluate_flow(scene_, mode(i), y, u, flow_);
    dydt = flow_.xdot;
  };
  detail::integrate_adaptive(rhs, x, t_begin(i), t0, options_.variational);
  return x;
}

}  // namespace saltus
