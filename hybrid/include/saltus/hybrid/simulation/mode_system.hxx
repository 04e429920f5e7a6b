// Definitions of mode_system.hpp.
#pragma once

#include <cmath>
#include <limits>
#include <saltus/hybrid/simulation/mode_system.hpp>

namespace saltus {

template <Scene S>
void ModeSystem<S>::set_mode(const Mode<nc>& mode) {
  if (!(mode == mode_)) sliding_contact_ = -1;
  mode_ = mode;
  guards_ = active_guards(scene_, mode);
}

template <Scene S>
void ModeSystem<S>::set_sliding(int contact, const Mode<nc>& open_mode, double force_floor) {
  SALTUS_REQUIRE(contact >= 0 && contact < nc && mode_[contact].closed() && !open_mode[contact].closed(),
                 "set_sliding: contact ", contact, " must be closed in the mode and open in open_mode");
  SALTUS_REQUIRE(force_floor >= 0 && std::isfinite(force_floor), "set_sliding: force_floor must be >= 0");
  sliding_contact_ = contact;
  sliding_open_mode_ = open_mode;
  sliding_force_floor_ = force_floor;
}

template <Scene S>
auto ModeSystem<S>::input(double t, const State& x) -> Input {
  if (t >= input_jump_) t = input_left_limit_;
  if (sliding_contact_ < 0) return input_(t, x, mode_);
  return sliding_input(scene_, input_, t, x, mode_, sliding_contact_, sliding_open_mode_, sliding_force_floor_,
                       sliding_flow_);
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
