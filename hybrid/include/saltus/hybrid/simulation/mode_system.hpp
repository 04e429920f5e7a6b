// One mode as an ODE for an integrator: x' = f_mode(x, u(t, x, mode)), with its guards and the
// constraints of its closed contacts. Inputs are either open loop, u(t), or feedback,
// u(t, x, mode), as tracking controllers need.
#pragma once

#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/guards.hpp>
#include <saltus/hybrid/vocabulary/input_law.hpp>

#include <array>
#include <cmath>
#include <functional>
#include <limits>

namespace saltus {


/// The equivalent control of a contact sliding on the surface (ModeSystem::set_sliding): u =
/// a u(t, x, mode) + (1 - a) u(t, x, open_mode), a in [0, 1], with the normal force of `contact` in
/// `mode` equal to force_floor where a in (0, 1) exists (a = 1 when the closed mode's input keeps
/// it above, a = 0 when the open mode's input brings it below). `ws`: a workspace for the two force
/// evaluations. The law is called with open_mode first and mode last.
template <Scene S>
VecT<double, S::nu> sliding_input(const S& scene, const InputLaw<S>& law, double t, const VecT<double, 2 * S::nq>& x,
                                  const Mode<S::nc>& mode, int contact, const Mode<S::nc>& open_mode,
                                  double force_floor, FlowWorkspace<S>& ws) {
  const VecT<double, S::nu> u_open = law(t, x, open_mode);
  const VecT<double, S::nu> u_closed = law(t, x, mode);
  evaluate_flow(scene, mode, x, u_closed, ws);
  const double lambda_closed = ws.force[contact].normal;
  if (lambda_closed >= force_floor) return u_closed;
  evaluate_flow(scene, mode, x, u_open, ws);
  const double lambda_open = ws.force[contact].normal;
  if (lambda_open <= force_floor) return u_open;
  const double a = (lambda_open - force_floor) / (lambda_open - lambda_closed);  // lambda_n is affine in u
  return a * u_closed + (1.0 - a) * u_open;
}

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

  /// Sets the mode; a change of mode ends a sliding motion (set_sliding).
  void set_mode(const Mode<nc>& mode);
  const Mode<nc>& mode() const { return mode_; }

  /// A sliding motion of contact `contact` (closed in the current mode, at the surface and at
  /// rest) under an input law that switches with the contact mode so that no mode is consistent
  /// (TransitionResolver::select_consistent): closed, the law's input u_c = u(t, x, mode) pulls
  /// (lambda_n < 0); open (`open_mode`), its input u_o = u(t, x, open_mode) drives the contact
  /// into the surface. The motion is Filippov's sliding solution with the equivalent control
  /// (A. F. Filippov, Differential Equations with Discontinuous Righthand Sides, Kluwer 1988,
  /// ch. 2 par. 4; V. I. Utkin, Sliding Modes in Control and Optimization, Springer 1992, ch. 2):
  /// the contact stays closed and input() returns u = a u_c + (1 - a) u_o with a in [0, 1] such
  /// that the contact's normal force in the current mode is `force_floor` (>= 0; lambda_n is
  /// affine in u). When u_c alone keeps lambda_n >= force_floor, a = 1 (the plain law); when u_o
  /// does not, a = 0 and lambda_n falls below zero, which fires the release guard (lift-off).
  /// The law is evaluated in open_mode first and in the current mode last, so that a law that
  /// keeps a history of the modes it is called with (a reference-spreading controller) records
  /// the mode being integrated. @pre mode()[contact] closed, open_mode[contact] open.
  void set_sliding(int contact, const Mode<nc>& open_mode, double force_floor);
  /// The sliding contact (set_sliding), -1 when none.
  int sliding_contact() const { return sliding_contact_; }
  const Mode<nc>& sliding_open_mode() const { return sliding_open_mode_; }
  double sliding_force_floor() const { return sliding_force_floor_; }
  const GuardList<nc>& guards() const { return guards_; }
  const S& scene() const { return scene_; }
  const InputLaw<S>& input_law() const { return input_; }

  /// u(t, x, mode()); while a contact slides (set_sliding), the equivalent control. At t >= the
  /// input jump (set_input_jump), the law is evaluated at the largest double below it.
  Input input(double t, const State& x);

  /// The time of the next input breakpoint (SimulationOptions::breakpoints) of the integration
  /// under way, +inf for none: evaluations at t >= t_jump take the law at the largest double below
  /// t_jump, its left limit, so that the step that ends at the breakpoint integrates, and its
  /// guards see, the input before a jump there (Dormand-Prince evaluates its last stages at the
  /// step's end). The input after the jump is the next integration's.
  void set_input_jump(double t_jump) {
    input_jump_ = t_jump;
    input_left_limit_ = std::nextafter(t_jump, -std::numeric_limits<double>::infinity());
  }

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
  FlowWorkspace<S> sliding_flow_;  ///< the equivalent control's force evaluations
  int sliding_contact_ = -1;
  Mode<nc> sliding_open_mode_{};
  double sliding_force_floor_ = 0.0;
  long rhs_evaluations_ = 0;
  double input_jump_ = std::numeric_limits<double>::infinity();
  double input_left_limit_ = std::numeric_limits<double>::max();
};

}  // namespace saltus
