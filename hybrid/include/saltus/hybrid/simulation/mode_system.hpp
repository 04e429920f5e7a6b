// One mode as an ODE for an integrator: x' = f_mode(x, u(t, x, mode)), with its guards and the
// constraints of its closed contacts. Inputs are either open loop, u(t), or feedback,
// u(t, x, mode), as tracking controllers need.
#pragma once

#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/guards.hpp>
#include <saltus/hybrid/vocabulary/input_law.hpp>

#include <array>
#include <functional>

namespace saltus {


/// The flow, guards and constraints of one mode under an input law. Owns its workspaces, so
/// evaluations allocate nothing (the input law may, if the user's does).
template <Scene S>
class ModeSystem {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  ModeSystem(const S& scene, const InputLaw<S>& input) : scene_(scene), input_(input) {}

  void set_mode(const Mode<nc>& mode) {
    mode_ = mode;
    guards_ = active_guards(scene_, mode);
  }
  const Mode<nc>& mode() const { return mode_; }
  const GuardList<nc>& guards() const { return guards_; }
  const S& scene() const { return scene_; }
  const InputLaw<S>& input_law() const { return input_; }

  Input input(double t, const State& x) const { return input_(t, x, mode_); }

  /// x' at (t, x).
  void rhs(double t, const State& x, State& xdot) {
    const Input u = input(t, x);
    evaluate_flow(scene_, mode_, x, u, flow_);
    xdot = flow_.xdot;
    ++rhs_evaluations_;
  }

  /// All guard values at (t, x), in the order of guards().
  template <class Out>
  void guard_values(double t, const State& x, Out& g) {
    const Input u = input(t, x);
    evaluate_flow(scene_, mode_, x, u, flow_);
    for (int k = 0; k < guards_.count; ++k) g[k] = guard_value(scene_, mode_, guards_[k], flow_);
  }

  /// Rate of a guard along the flow, d/dt gamma(t, x(t)), by a central difference along the
  /// flow over +-dt (the input law included). Only its sign is used, to decide whether a guard
  /// sitting at zero at an event is about to cross (a chained transition).
  double guard_rate(double t, const State& x, const Guard& g, double dt = 1e-7) {
    int k = 0;
    while (k < guards_.count && !(guards_[k] == g)) ++k;
    SALTUS_DEMAND(k < guards_.count, InvalidArgument, "guard_rate: the guard is not active in this mode");
    State f;
    rhs(t, x, f);
    const double h = dt * std::max(1.0, std::abs(t));
    std::array<double, 2 * S::nc + 1> gp{}, gm{};
    guard_values(t + h, State(x + h * f), gp);
    guard_values(t - h, State(x - h * f), gm);
    return (gp[k] - gm[k]) / (2 * h);
  }

  const FlowWorkspace<S>& flow_workspace() const { return flow_; }
  long rhs_evaluations() const { return rhs_evaluations_; }

 private:
  const S& scene_;
  InputLaw<S> input_;
  Mode<nc> mode_{};
  GuardList<nc> guards_{};
  FlowWorkspace<S> flow_;
  long rhs_evaluations_ = 0;
};

}  // namespace saltus
