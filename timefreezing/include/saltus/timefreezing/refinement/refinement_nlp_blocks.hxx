// The local blocks of the refinement NLP (refinement_nlp.hpp, "DERIVATIVES"): templated on the
// scalar, evaluated at double, first-order and second-order dual numbers.
#pragma once

#include <saltus/hybrid/dynamics/flow.hxx>
#include <saltus/hybrid/dynamics/kinematics.hxx>
#include <saltus/hybrid/dynamics/jump_map.hxx>
#include <saltus/timefreezing/refinement/refinement_nlp.hpp>

#include <algorithm>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
template <class T>
VecT<T, S::nu> ScheduleRefinementNlp<S, Ocp>::input_law(const T& t, const VecT<T, S::nu>& decision) const {
  if constexpr (HasInputLaw<Ocp, T, nu>) return ocp_.template input<T>(t, decision);
  else return decision;
}

/// The validity values of phase p's mode at a flow evaluation at phase fraction theta, in the order
/// of the file comment, written from out[nx + 1] on. The cone rows of a sticking group's leader read the group's totals
/// (refinement_nlp.hpp, "IMPLIED ROWS" (d)).
template <Scene S, class Ocp>
template <class T>
void ScheduleRefinementNlp<S, Ocp>::write_validity(int p, double theta, const FlowWorkspace<S, T>& ws,
                                                   VecT<T, stage_outputs>& out) const {
  const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
  const std::array<int, nc>& leader = friction_leader_[static_cast<std::size_t>(p)];
  int k = nx + 1;
  for (int i = 0; i < nc; ++i) {
    const ContactState& c = mode[i];
    if (!c.closed()) {
      const auto& ci = ws.kin.contacts[i];
      if (theta == 0.0 && released_at_start(p, i)) out[k++] = ci.wn.dot(ws.acceleration) + ci.kappa_n;  // RELEASE CONSISTENCY
      else out[k++] = ci.gap - T(clearance(p, i, theta));
      continue;
    }
    out[k++] = ws.force[i].normal - T(normal_margin(p, i, theta));
    if (scene_.contact(i).tangents() == 0) continue;
    if (c.mode == ContactMode::Slip) {
      out[k++] = T(c.slip_direction[0]) * ws.kin.contacts[i].zeta_t[0] - T(slip_margin(p, i, theta));
      continue;
    }
    const double inside = 1.0 - options_.stick_cone_margin;  // RefinementOptions::stick_cone_margin
    T mu_lambda = T(inside * scene_.contact(i).mu) * ws.force[i].normal, lambda_t = ws.force[i].tangent[0];
    if (leader[i] == i)
      for (int j = i + 1; j < nc; ++j)
        if (leader[j] == i) {
          mu_lambda += T(inside * scene_.contact(j).mu) * ws.force[j].normal;
          lambda_t += ws.force[j].tangent[0];
        }
    out[k++] = mu_lambda - lambda_t;
    out[k++] = mu_lambda + lambda_t;
  }
}

/// RefinementOptions::flight_clearance for open contact i of phase p at phase fraction theta: a
/// hump of height flight_clearance, 0 at the phase's ends, of the order the gap can follow there.
/// A touchdown ends the phase with an approach speed: the gap falls linearly, (1 - s). A release
/// (lambda_n = 0, no impact) starts it with h_n = zeta_n = 0 and zeta_n' = 0 (the free acceleration
/// equals the constrained one where lambda_n = 0), so the gap rises like s^3 and a linear hump
/// would ask for a jerk of order clearance / (s^3 d_p^3) at the first stage points: the hump
/// is (256/27) s^3 (1 - s) there (its peak 1 at s = 3/4). Any other start (the initial state, an
/// impact that opens the contact): 4 s (1 - s).
template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::clearance(int p, int i, double theta) const {
  if (options_.flight_clearance == 0.0) return 0.0;
  const double hump = released_at_start(p, i) ? 256.0 / 27.0 * theta * theta * theta * (1.0 - theta) : 4.0 * theta * (1.0 - theta);
  return options_.flight_clearance * hump;
}

/// Whether open contact i of phase p was closed in phase p - 1 and opened by a release (the event
/// has no impact). Read from the schedule: the event rows (events_) are built after the first
/// evaluations of the blocks.
template <Scene S, class Ocp>
bool ScheduleRefinementNlp<S, Ocp>::released_at_start(int p, int i) const {
  return p > 0 && schedule_.phases[static_cast<std::size_t>(p - 1)][i].closed() &&
         !schedule_.phases[static_cast<std::size_t>(p)][i].closed() &&
         !schedule_.events[static_cast<std::size_t>(p - 1)].impact();
}

/// The lower bound of closed contact i's lambda_n in phase p at phase fraction theta [N]:
/// RefinementOptions::normal_force_margin when the schedule keeps the contact closed past the
/// phase's end, RefinementOptions::stance_load 4 theta (1 - theta) when it releases it there (by the
/// guard lambda_n = 0), stance_load itself when it releases it at an input jump
/// (RefinementOptions::releases_at_input_jumps: the force need not fall to 0 at the end, and a
/// stance that starts at a touchdown with lambda_n = 0 may open again at once under its input);
/// at least RefinementOptions::touchdown_load (1 - 4 theta) when a touchdown of i starts the phase.
template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::normal_margin(int p, int i, double theta) const {
  const std::size_t next = static_cast<std::size_t>(p) + 1;
  const bool kept = next == schedule_.phases.size() || schedule_.phases[next][i].closed();
  const double bound = kept                               ? options_.normal_force_margin
                       : options_.releases_at_input_jumps ? options_.stance_load
                                                          : options_.stance_load * 4.0 * theta * (1.0 - theta);
  const bool landed = p > 0 && schedule_.events[static_cast<std::size_t>(p - 1)].has(i, GuardKind::Touchdown);
  return landed ? std::max(bound, options_.touchdown_load * (1.0 - 4.0 * theta)) : bound;
}

/// The lower bound of slipping contact i's speed s zeta_t in phase p at phase fraction theta [m/s]:
/// RefinementOptions::slip_speed_margin, ramped linearly from 0 over the first quarter of the phase
/// when a slip onset of i starts it (the slide starts from rest) and to 0 over the last quarter
/// when a stop of i ends it.
template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::slip_margin(int p, int i, double theta) const {
  if (options_.slip_speed_margin == 0.0) return 0.0;
  const std::size_t q = static_cast<std::size_t>(p);
  double w = 1.0;
  if (p > 0 && schedule_.events[q - 1].has(i, GuardKind::SlipOnset)) w = std::min(w, 4.0 * theta);
  if (q < schedule_.events.size() && schedule_.events[q].has(i, GuardKind::Stop)) w = std::min(w, 4.0 * (1.0 - theta));
  return options_.slip_speed_margin * w;
}

template <Scene S, class Ocp>
template <class T>
VecT<T, ScheduleRefinementNlp<S, Ocp>::stage_outputs> ScheduleRefinementNlp<S, Ocp>::stage_block(
    int e, double theta, const VecT<T, nw>& w, FlowWorkspace<S, T>& ws) const {
  const int p = phase_of(e);
  const T& t_begin = w[nx + nu];
  const T& t_end = w[nx + nu + 1];
  const T h = (t_end - t_begin) * T(element_length_scaled_[std::size_t(e)]) / T(double(elements_in(p)));
  const T t = t_begin + T(theta) * (t_end - t_begin);
  const VecT<T, nu> u = input_law<T>(t, VecT<T, nu>(w.template segment<nu>(nx)));
  return stage_values<T>(e, theta, VecT<T, nx>(w.template head<nx>()), u, h, t, ws);
}

template <Scene S, class Ocp>
template <class T>
VecT<T, ScheduleRefinementNlp<S, Ocp>::stage_outputs> ScheduleRefinementNlp<S, Ocp>::stage_values(
    int e, double theta, const VecT<T, nx>& x, const VecT<T, nu>& u, const T& h, [[maybe_unused]] const T& t,
    FlowWorkspace<S, T>& ws) const {
  const int p = phase_of(e);
  const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
  ws.constraint_stabilisation = options_.contact_stabilisation;
  evaluate_flow<S, T>(scene_, mode, x, u, ws);
  VecT<T, stage_outputs> out = VecT<T, stage_outputs>::Zero();
  out.template head<nx>() = h * ws.xdot;
  T running(0.0);
  if constexpr (HasTimedRunningCost<Ocp, T, nx, nu>) running = ocp_.template running_cost<T>(x, u, t);
  else if constexpr (HasRunningCost<Ocp, T, nx, nu>) running = ocp_.template running_cost<T>(x, u);
  out[nx] = h * running;
  write_validity<T>(p, theta, ws, out);
  if constexpr (np > 0) out.template segment<np>(nx + 1 + max_validity) = ocp_.template path_constraints<T>(x, u);
  return out;
}

template <Scene S, class Ocp>
template <class T>
VecT<T, ScheduleRefinementNlp<S, Ocp>::event_outputs> ScheduleRefinementNlp<S, Ocp>::event_block(
    int b, const VecT<T, nwe>& w, FlowWorkspace<S, T>& fws, JumpWorkspace<S, T>& jws) const {
  const EventRows& ev = events_[static_cast<std::size_t>(b)];
  const Mode<nc>& before = schedule_.phases[static_cast<std::size_t>(b)];
  const Mode<nc>& after = schedule_.phases[static_cast<std::size_t>(b + 1)];
  const VecT<T, nx> x_minus = w.template head<nx>();
  const VecT<T, nu> u = input_law<T>(w[nx + nu], VecT<T, nu>(w.template segment<nu>(nx)));
  fws.constraint_stabilisation = options_.contact_stabilisation;
  evaluate_flow<S, T>(scene_, before, x_minus, u, fws);  // the forces of the ending phase, and ws.kin at x-
  VecT<T, event_outputs> out = VecT<T, event_outputs>::Zero();
  int k = 0;
  for (const Guard& g : ev.imposed_guards) {
    const auto& c = fws.kin.contacts[g.contact];
    const ContactForce<T>& f = fws.force[g.contact];
    switch (g.kind) {
      case GuardKind::Touchdown: out[k] = c.gap; break;
      case GuardKind::Release: out[k] = f.normal; break;
      case GuardKind::Stop: out[k] = c.zeta_t[0]; break;
      case GuardKind::SlipOnset:
        out[k] = f.tangent[0] + T(after[g.contact].slip_direction[0] * scene_.contact(g.contact).mu) * f.normal;
        break;
    }
    ++k;
  }
  for (int i : ev.released_sticking) out[k++] = fws.force[i].tangent[0];
  k = 2 * nc;
  for (int i : ev.approach_contacts) out[k++] = fws.kin.contacts[i].zeta_n;
  VecT<T, nx> x_plus = x_minus;
  if (ev.impact) apply_jump_map<S, T>(scene_, ev.impulse_mode, x_minus, jws, x_plus);
  out.template segment<nx>(3 * nc) = x_plus;
  if (!ev.impact) return out;
  // jws.kin holds the kinematics at x- (q is continuous): zeta at x+ from the Jacobians there.
  const VecT<T, nq> v_plus = x_plus.template tail<nq>();
  k = 3 * nc + nx;
  for (int i = 0; i < nc; ++i) {
    const ImpulseMode& role = ev.impulse_mode[i];
    if (role.role == ImpulseRole::None) continue;
    const ContactForce<T>& impulse = jws.impulse[i];
    out[k++] = impulse.normal;
    if (scene_.contact(i).tangents() == 0) continue;
    const T mu_impulse = T(scene_.contact(i).mu) * impulse.normal;
    if (role.role == ImpulseRole::Stick) {
      out[k++] = mu_impulse - impulse.tangent[0];
      out[k++] = mu_impulse + impulse.tangent[0];
    } else {
      out[k++] = T(role.slip_direction[0]) * T(jws.kin.contacts[i].Wt.col(0).dot(v_plus));
    }
  }
  (void)before;
  k = 6 * nc + nx;
  for (int i : ev.separating_contacts) out[k++] = jws.kin.contacts[i].wn.dot(v_plus);
  return out;
}

template <Scene S, class Ocp>
template <class T>
VecT<T, ScheduleRefinementNlp<S, Ocp>::terminal_outputs> ScheduleRefinementNlp<S, Ocp>::terminal_block(
    const VecT<T, nwt>& w) const {
  VecT<T, terminal_outputs> out = VecT<T, terminal_outputs>::Zero();
  const VecT<T, nx> x = w.template head<nx>();
  if constexpr (nt > 0) out.template head<nt>() = ocp_.template terminal_constraints<T>(x, w[nx]);
  if constexpr (HasTerminalCost<Ocp, T, nx>) out[nt] = ocp_.template terminal_cost<T>(x, w[nx]);
  return out;
}

}  // namespace saltus::timefreezing
