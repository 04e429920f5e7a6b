// Definitions of jump_gain.hpp (see there for the derivation).
#pragma once

#include <saltus/sensitivity/jump_gain.hpp>

namespace saltus {

template <Scene S>
JumpGainSolver<S>::JumpGainSolver(const S& scene, JumpGainOptions options, int reserved_transitions)
    : scene_(scene), options_(options), ws_(std::make_unique<DerivativeWorkspace<S>>()) {
  SALTUS_REQUIRE(options.grazing_threshold >= 0 && options.input_rate_step > 0 && options.chain_time_tolerance >= 0 &&
                    options.feedback_step > 0, "JumpGainOptions: grazing_threshold >= 0, input_rate_step > 0, ",
                "chain_time_tolerance >= 0 and feedback_step > 0 are required");
  gain_.info.reserve(reserved_transitions);
}

template <Scene S>
auto JumpGainSolver<S>::compute(const Event<S>& event, const InputLaw<S>& law) -> const JumpGain<S>& {
  SALTUS_REQUIRE(!event.transitions.empty(), "jump gain: the event at t = ", event.t,
                " has no transitions");
  SALTUS_REQUIRE(static_cast<bool>(law), "jump gain: the input law is empty");
  const double t = event.t;
  auto& g = gain_;
  g.transitions = static_cast<int>(event.transitions.size());
  g.info.resize(event.transitions.size());
  g.jump_map_residual = 0.0;
  // Z_z, Z_v: z_k = Z_z z- + Z_v v;  d_z, d_v: dt_k = d_z z- + d_v v (C.40-C.42 recursion).
  Zz_.setIdentity();
  Zv_.setZero();
  dz_.setZero();
  dv_.setZero();
  bool first_guarded = true;
  for (std::size_t k = 0; k < event.transitions.size(); ++k) {
    const Transition<S>& tr = event.transitions[k];
    TransitionGainInfo& info = g.info[k];
    info = TransitionGainInfo{};
    // Flow of the mode before at the transition's state (f_{k-1}), with its own input.
    u_before_ = law(t, tr.x_before, tr.mode_before);
    flow_jacobian(scene_, tr.mode_before, tr.x_before, u_before_, *ws_, f_before_, A_, B_);
    if (k == 0) g.f_minus = f_before_;

    if (!tr.guards.empty()) {
      if (tr.guards.size() != 1)
        throw SimultaneousActivation(detail::concat("jump gain: transition ", k,
                    " of the event at t = ", t, " is fired by ", tr.guards.size(),
                    " guards at once; its first-order gain is conewise (one per activation order) and is "
                    "not computed by JumpGainSolver"));
      const Guard& guard = tr.guards.front();
      info.guarded = true;
      info.gamma = guard_gradient(scene_, tr.mode_before, guard, tr.x_before, u_before_, *ws_, dgx_, dgu_);
      // mu'-: total derivative of the input law along the flow of the mode before (C.24), a
      // Richardson-extrapolated central difference (4 D(h/2) - D(h)) / 3, O(h^4): laws that
      // blend gains over a few ms (references::hopper_push_off) have large third derivatives,
      // and the plain O(h^2) difference cost 1e-5 relative in the event time there.
      const double h = options_.input_rate_step * std::max(1.0, std::abs(t));
      input_rate(law, t, tr.x_before, tr.mode_before, h, u_dot_);
      input_rate(law, t, tr.x_before, tr.mode_before, 0.5 * h, u_rate_half_);
      u_dot_ = (4.0 * u_rate_half_ - u_dot_) / 3.0;
      const double state_rate = dgx_.dot(f_before_);
      const double input_rate = nu > 0 ? dgu_.dot(u_dot_) : 0.0;
      info.gamma_dot = state_rate + (options_.include_input_rate ? input_rate : 0.0);
      info.rate_scale = dgx_.norm() * f_before_.norm() + (nu > 0 ? dgu_.norm() * u_dot_.norm() : 0.0);
      info.immediate = !first_guarded && info.gamma < -options_.chain_time_tolerance * info.rate_scale;
      if (!info.immediate) {
        if (!(std::abs(info.gamma_dot) > options_.grazing_threshold * info.rate_scale) ||
            !std::isfinite(info.gamma_dot)) {
          throw GrazingEvent(
              detail::concat("jump gain: near-grazing ", to_string(guard.kind), " of contact '",
                             scene_.contact(guard.contact).name, "' at t = ", t, " (transition ", k,
                             "): |gamma_dot| = ", std::abs(info.gamma_dot), " <= ", options_.grazing_threshold,
                             " * rate scale ", info.rate_scale, " (Dgamma_x f = ", state_rate,
                             ", Dgamma_u u' = ", input_rate, options_.include_input_rate ? "" : ", left out", ")"),
              t, guard, info.gamma_dot, info.rate_scale);
        }
        // Closed loop: the input moves with the state deviation (see "Feedback" above). Only
        // here: gamma_dot and the rate scale use the open-loop Dgamma_x (mu'- holds K f).
        if constexpr (nu > 0) {
          if (options_.feedback == FeedbackTreatment::ClosedLoop) {
            feedback_gain<S>(law, t, tr.x_before, tr.mode_before, options_.feedback_step, x_probe_, K_);
            dgx_.noalias() += dgu_ * K_;
          }
        }
        // dt_k = -(Dgamma_x z_{k-1} + Dgamma_u v) / gamma_dot_k   (C.22, C.29)
        dz_.noalias() = -(dgx_ * Zz_) / info.gamma_dot;
        if constexpr (nu > 0) {
          dv_.noalias() = -(dgx_ * Zv_) / info.gamma_dot;
          dv_ -= dgu_ / info.gamma_dot;
        }
        if (first_guarded) {
          g.dt_dz = dz_;
          g.dt_dv = dv_;
        }
      }
      first_guarded = false;
    }

    // The jump map: the impulse of an impact, the identity for a mode change (A.34-A.49).
    if (tr.impact) {
      jump_map_jacobian(scene_, tr.impulse_mode, tr.x_before, *ws_, x_jump_, Dg_);
      g.jump_map_residual = std::max(g.jump_map_residual, (x_jump_ - tr.x_after).cwiseAbs().maxCoeff());
    } else {
      Dg_.setIdentity();
    }
    // Flow of the mode after at the transition's state (f_k), with its own input.
    u_after_ = law(t, tr.x_after, tr.mode_after);
    evaluate_flow(scene_, tr.mode_after, tr.x_after, u_after_, flow_);
    f_after_ = flow_.xdot;
    if (k + 1 == event.transitions.size()) g.f_plus = f_after_;

    // z_k = Dg (z_{k-1} + f_{k-1} dt_k) - f_k dt_k.
    jump_f_.noalias() = Dg_ * f_before_;
    jump_f_ -= f_after_;
    Zz_ = (Dg_ * Zz_).eval();
    Zz_.noalias() += jump_f_ * dz_;
    if constexpr (nu > 0) {  // (a product with a fixed nx x 0 matrix trips Eigen's GEMM checks)
      Zv_ = (Dg_ * Zv_).eval();
      Zv_.noalias() += jump_f_ * dv_;
    }
  }
  g.G_z = Zz_;
  g.G_v = Zv_;
  return g;
}

template <Scene S>
void JumpGainSolver<S>::input_rate(const InputLaw<S>& law, double t, const State& x, const Mode<nc>& mode, double h,
                                   Input& out) {
  x_probe_ = x + h * f_before_;
  out = law(t + h, x_probe_, mode);
  x_probe_ = x - h * f_before_;
  out -= law(t - h, x_probe_, mode);
  out /= 2 * h;
}

template <Scene S>
void feedback_gain(const InputLaw<S>& law, double t, const Vec<2 * S::nq>& x, const Mode<S::nc>& mode, double step,
                   Vec<2 * S::nq>& probe, Mat<S::nu, 2 * S::nq>& K) {
  constexpr int nx = 2 * S::nq;
  probe = x;
  for (int j = 0; j < nx; ++j) {
    const double h = step * std::max(1.0, std::abs(x[j]));
    probe[j] = x[j] + h;
    K.col(j) = law(t, probe, mode);
    probe[j] = x[j] - h;
    K.col(j) -= law(t, probe, mode);
    K.col(j) /= 2 * h;
    probe[j] = x[j];
  }
}

template <Scene S>
std::vector<JumpGain<S>> jump_gains(const S& scene, const HybridTrajectory<S>& traj, const JumpGainOptions& options) {
  JumpGainSolver<S> solver(scene, options);
  std::vector<JumpGain<S>> gains;
  gains.reserve(traj.events.size());
  for (const auto& ev : traj.events) gains.push_back(solver.compute(ev, traj.input));
  return gains;
}

}  // namespace saltus
