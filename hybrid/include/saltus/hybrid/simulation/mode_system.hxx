// Definitions of mode_system.hpp.
#pragma once

#include <limits>
#include <saltus/hybrid/simulation/mode_system.hpp>

namespace saltus {

template <Scene S>
void ModeSystem<S>::set_mode(const Mode<nc>& mode) {
  mode_ = mode;
  guards_ = active_guards(scene_, mode);
}

template <Scene S>
void ModeSystem<S>::rhs(double t, const State& x, State& xdot) {
  const Input u = input(t, x);
  evaluate_flow(scene_, mode_, x, u, flow_);
  xdot = flow_.xdot;
  ++rhs_evaluations_;
}

template <Scene S>
double ModeSystem<S>::guard_rate(double t, const State& x, const Guard& g, double dt) {
  int k = 0;
  while (k < guards_.count && !(guards_[k] == g)) ++k;
  SALTUS_REQUIRE(k < guards_.count, "guard_rate: the guard is not active in this mode");
  State f;
  rhs(t, x, f);
  const double h = dt * std::max(1.0, std::abs(t));
  std::array<double, 2 * S::nc + 1> gp{}, gm{};
  guard_values(t + h, State(x + h * f), gp);
  guard_values(t - h, State(x - h * f), gm);
  return (gp[k] - gm[k]) / (2 * h);
}

template <Scene S>
void ModeSystem<S>::guard_values(double t, const State& x, GuardValues& g, GuardValues* rates) {
  const Input u = input(t, x);
  evaluate_flow(scene_, mode_, x, u, flow_);
  for (int k = 0; k < guards_.count; ++k) g[k] = guard_value(scene_, mode_, guards_[k], flow_);
  if (rates) {
    for (int k = 0; k < guards_.count; ++k)
      (*rates)[k] = guards_[k].kind == GuardKind::Touchdown ? flow_.kin.contacts[guards_[k].contact].zeta_n
                                                            : std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace saltus
