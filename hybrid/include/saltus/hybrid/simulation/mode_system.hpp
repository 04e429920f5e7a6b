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
  /// One value per guard of the mode, in the order of guards() (at most 2 nc + 1).
  using GuardValues = std::array<double, 2 * S::nc + 1>;

  /// The scene must outlive the mode system (a temporary scene does not compile).
  ModeSystem(const S& scene, const InputLaw<S>& input) : scene_(scene), input_(input) {}
  ModeSystem(S&&, const InputLaw<S>&) = delete;  // keeps a reference: would dangle

  void set_mode(const Mode<nc>& mode);
  const Mode<nc>& mode() const { return mode_; }
  const GuardList<nc>& guards() const { return guards_; }
  const S& scene() const { return scene_; }
  const InputLaw<S>& input_law() const { return input_; }

  Input input(double t, const State& x) const { return input_(t, x, mode_); }

  /// x' at (t, x).
  void rhs(double t, const State& x, State& xdot);

  /// All guard values at (t, x), in the order of guards(). With `rates`, also the exact rate
  /// d/dt gamma of every touchdown guard (the gap's rate, the normal velocity zeta_n = w_n^T v;
  /// q' = v); the other guards' slots are NaN (their rates need the force's derivative).
  void guard_values(double t, const State& x, GuardValues& g, GuardValues* rates = nullptr);

  /// Rate of a guard along the flow, d/dt gamma(t, x(t)), by a central difference along the
  /// flow over +-dt (the input law included). Only its sign is used, to decide whether a guard
  /// sitting at zero at an event is about to cross (a chained transition).
  double guard_rate(double t, const State& x, const Guard& g, double dt = 1e-7);

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
