// Definitions of jump_gain.hpp (see there for the derivation).
#pragma once

#include <saltus/sensitivity/jump_gain.hpp>

namespace saltus {

template <Scene S>
JumpGainSolver<S>::JumpGainSolver(const S& scene, JumpGainOptions options, int reserved_transitions)
    : scene_(scene), options_(options), ws_(std::make_unique<DerivativeWorkspace<S>>()) {
  SALTUS_REQUIRE(options.grazing_threshold >= 0 && options.input_rate_step > 0 && options.chain_time_tolerance >= 0 &&
                    options.feedback_step > 0 && options.jump_map_tolerance >= 0,
                "JumpGainOptions: grazing_threshold >= 0, input_rate_step > 0, chain_time_tolerance >= 0, "
                "feedback_step > 0 and jump_map_tolerance >= 0 are required");
  gain_.info.reserve(reserved_transitions);
}

template <Scene S>
auto JumpGainSolver<S>::compute(const Event<S>& event, const InputLaw<S>& law) -> const JumpGain<S>& {
  return compute(event, law, Mat<nx, nx>::Identity(), Mat<nx, nu>::Zero());
}

template <Scene S>
auto JumpGainSolver<S>::compute(const Event<S>& event, const InputLaw<S>& law, const Mat<nx, nx>& incoming_z,
                                const Mat<nx, nu>& incoming_v) -> const JumpGain<S>& {
  SALTUS_REQUIRE(!event.transitions.empty(), "jump gain: the event at t = ", event.t,
                " has no transitions");
  SALTUS_REQUIRE(static_cast<bool>(law), "jump gain: the input law is empty");
  const double t = event.t;
  auto& g = gain_;
  g.transitions = static_cast<int>(event.transitions.size());
  g.info.resize(event.transitions.size());
  g.jump_map_residual = 0.0;
  // Z_z, Z_v: z_k = Z_z z- + Z_v v;  d_z, d_v: dt_k = d_z z- + d_v v (C.40-C.42 recursion).
  Zz_ = incoming_z;
  Zv_ = incoming_v;
  dz_.setZero();
  dv_.setZero();
  g.dt_dz.setZero();  // stays 0 for a fixed-time event (no guard, or fired by an input jump)
  g.dt_dv.setZero();
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
      const Guard& guard = tr.guards.front();
      info.guarded = true;
      evaluate_crossing(law, t, tr.x_before, tr.mode_before, guard, f_before_);
      const GuardCrossing<S>& c = crossing_;
      info.gamma = c.gamma;
      info.gamma_dot = c.gamma_dot;
      info.rate_scale = c.rate_scale;
      // The first transition of an event fired by an input jump (Event::input_jump) has the
      // breakpoint's time, dt = 0; a later one clearly below zero when the previous one ends is
      // immediate (dt_k = dt_{k-1}). Either does not move with the state.
      info.immediate = first_guarded ? event.input_jump
                                     : info.gamma < -options_.chain_time_tolerance * info.rate_scale;
      if (!info.immediate && tr.guards.size() != 1) {
        // Guards that fire together in every nearby motion (their first-order crossing-time
        // shifts are the same function of (z-, v), see "Coincident guards" in jump_gain.hpp)
        // have a linear gain: any one of them gives it. Otherwise the gain is conewise.
        double mismatch = 0.0;
        if (!coincident_guards(law, t, tr, mismatch))
          throw SimultaneousActivation(detail::concat("jump gain: transition ", k,
                      " of the event at t = ", t, " is fired by ", tr.guards.size(),
                      " guards at once whose crossing times split under perturbation (relative difference ",
                      mismatch, " of their first-order shifts); its first-order gain is conewise (one per activation "
                      "order, ConewiseJumpGain in conewise_gain.hpp), not computed by JumpGainSolver"));
        evaluate_crossing(law, t, tr.x_before, tr.mode_before, guard, f_before_);  // the check used crossing_
      }
      if (!info.immediate) {
        if (!(std::abs(info.gamma_dot) > options_.grazing_threshold * info.rate_scale) ||
            !std::isfinite(info.gamma_dot)) {
          throw GrazingEvent(
              detail::concat("jump gain: near-grazing ", to_string(guard.kind), " of contact '",
                             scene_.contact(guard.contact).name, "' at t = ", t, " (transition ", k,
                             "): |gamma_dot| = ", std::abs(info.gamma_dot), " <= ", options_.grazing_threshold,
                             " * rate scale ", info.rate_scale, " (Dgamma_x f = ", c.state_rate,
                             ", Dgamma_u u' = ", c.input_rate, options_.include_input_rate ? "" : ", left out", ")"),
              t, guard, info.gamma_dot, info.rate_scale);
        }
        dgx_ = c.dgamma_x;  // closed loop where asked (see "Feedback" above)
        dgu_ = c.dgamma_u;
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
      const double residual = (x_jump_ - tr.x_after).cwiseAbs().maxCoeff();
      g.jump_map_residual = std::max(g.jump_map_residual, residual);
      if (!(residual <= options_.jump_map_tolerance * std::max(1.0, tr.x_after.cwiseAbs().maxCoeff()))) {
        std::string roles;
        for (int i = 0; i < S::nc; ++i)
          if (tr.impulse_mode[i].role != ImpulseRole::None)
            roles += (roles.empty() ? "" : ", ") + scene_.contact(i).name + ": " + to_string(tr.impulse_mode[i].role);
        throw ContactProblemFailure(detail::concat(
            "jump gain: transition ", k, " of the event at t = ", event.t, " (impulse roles ", roles,
            "): the differentiated jump map gives a post-impact state ", residual,
            " from the transition's x+ (tolerance ", options_.jump_map_tolerance, " relative): its derivative is not that "
            "of the trajectory's jump, so no first-order gain is computed. Seen where redundant contacts slip together "
            "(four coplanar corners: the jump map and the impact solver split the impulse differently), and for "
            "trajectories made elsewhere (a recovered or imported reference) whose x+ is not the impact law's "
            "post-impact state, e.g. an unconverged time-freezing solution"));
      }
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
bool JumpGainSolver<S>::coincident_guards(const InputLaw<S>& law, double t, const Transition<S>& tr,
                                          double& mismatch) {
  // dt_g = -(dgamma_x (Z_z z- + Z_v v) + dgamma_u v) / gamma_dot for each guard g, as rows in (z-, v).
  using Row = Eigen::Matrix<double, 1, nx + nu>;
  Row first = Row::Zero();
  mismatch = 0.0;
  for (std::size_t i = 0; i < tr.guards.size(); ++i) {
    evaluate_crossing(law, t, tr.x_before, tr.mode_before, tr.guards[i], f_before_);
    const GuardCrossing<S>& c = crossing_;
    if (!(std::abs(c.gamma_dot) > options_.grazing_threshold * c.rate_scale))
      throw GrazingEvent(detail::concat("jump gain: near-grazing ", to_string(tr.guards[i].kind), " of contact '",
                                        scene_.contact(tr.guards[i].contact).name, "' at t = ", t, " (one of ",
                                        tr.guards.size(), " guards firing together): |gamma_dot| = ",
                                        std::abs(c.gamma_dot), " <= ", options_.grazing_threshold, " * rate scale ",
                                        c.rate_scale),
                         t, tr.guards[i], c.gamma_dot, c.rate_scale);
    Row row;
    row.template head<nx>() = -(c.dgamma_x * Zz_) / c.gamma_dot;
    if constexpr (nu > 0) row.template tail<nu>() = -(c.dgamma_x * Zv_ + c.dgamma_u) / c.gamma_dot;
    if (i == 0) {
      first = row;
      continue;
    }
    const double scale = std::max({first.norm(), row.norm(), 1e-300});
    mismatch = std::max(mismatch, (row - first).norm() / scale);
  }
  return mismatch <= options_.coincidence_tolerance;
}

template <Scene S>
auto JumpGainSolver<S>::crossing(const InputLaw<S>& law, double t, const State& x, const Mode<nc>& mode,
                                 const Guard& guard) -> const GuardCrossing<S>& {
  SALTUS_REQUIRE(static_cast<bool>(law), "guard crossing: the input law is empty");
  evaluate_flow(scene_, mode, x, law(t, x, mode), flow_);
  f_crossing_ = flow_.xdot;
  evaluate_crossing(law, t, x, mode, guard, f_crossing_);
  return crossing_;
}

template <Scene S>
void JumpGainSolver<S>::evaluate_crossing(const InputLaw<S>& law, double t, const State& x, const Mode<nc>& mode,
                                          const Guard& guard, const State& f) {
  GuardCrossing<S>& c = crossing_;
  f_before_ = f;  // input_rate() differences the law along f_before_
  const Input u = law(t, x, mode);
  c.gamma = guard_gradient(scene_, mode, guard, x, u, *ws_, c.dgamma_x, c.dgamma_u);
  // mu'-: total derivative of the input law along the flow of the mode (C.24), a
  // Richardson-extrapolated central difference (4 D(h/2) - D(h)) / 3, O(h^4): laws that
  // blend gains over a few ms (references::hopper_push_off) have large third derivatives,
  // and the plain O(h^2) difference cost 1e-5 relative in the event time there.
  const double h = options_.input_rate_step * std::max(1.0, std::abs(t));
  input_rate(law, t, x, mode, h, u_dot_);
  input_rate(law, t, x, mode, 0.5 * h, u_rate_half_);
  u_dot_ = (4.0 * u_rate_half_ - u_dot_) / 3.0;
  c.state_rate = c.dgamma_x.dot(f);
  c.input_rate = nu > 0 ? c.dgamma_u.dot(u_dot_) : 0.0;
  c.gamma_dot = c.state_rate + (options_.include_input_rate ? c.input_rate : 0.0);
  c.rate_scale = c.dgamma_x.norm() * f.norm() + (nu > 0 ? c.dgamma_u.norm() * u_dot_.norm() : 0.0);
  // Closed loop: the input moves with the state deviation (see "Feedback" in jump_gain.hpp).
  // Only here: gamma_dot and the rate scale use the open-loop Dgamma_x (mu'- holds K f).
  if constexpr (nu > 0) {
    if (options_.feedback == FeedbackTreatment::ClosedLoop) {
      feedback_gain<S>(law, t, x, mode, options_.feedback_step, x_probe_, K_);
      c.dgamma_x.noalias() += c.dgamma_u * K_;
    }
  }
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
