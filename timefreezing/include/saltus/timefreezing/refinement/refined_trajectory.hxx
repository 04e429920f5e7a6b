// The refined reference as a HybridTrajectory (refinement.hpp, RefinementResult::trajectory): one
// segment per phase, one polynomial piece per element, the schedule's events with their impulses,
// and the optimal input law.
#pragma once

#include <saltus/timefreezing/refinement/refinement.hpp>
#include <saltus/timefreezing/refinement/refinement_nlp_build.hxx>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace saltus::timefreezing {

namespace detail {

/// The collocation polynomial of an element through its start and its n_s stage values, in
/// theta = (t - t_start) / h (degree n_s).
template <int nx>
PolynomialPiece<nx> collocation_piece(double t_start, double h, const RadauIIA& tableau, const Vec<nx>& start,
                                      const std::vector<Vec<nx>>& stage_values) {
  const int ns = tableau.stages;
  Eigen::MatrixXd V(ns + 1, ns + 1);  // rows: theta = 0, c_1 .. c_ns; columns: powers
  Eigen::MatrixXd Y(ns + 1, nx);
  for (int r = 0; r <= ns; ++r) {
    const double th = r == 0 ? 0.0 : tableau.c[r - 1];
    for (int k = 0; k <= ns; ++k) V(r, k) = std::pow(th, k);
    Y.row(r) = (r == 0 ? start : stage_values[static_cast<std::size_t>(r - 1)]).transpose();
  }
  const Eigen::MatrixXd C = V.partialPivLu().solve(Y);
  PolynomialPiece<nx> piece;
  piece.t0 = t_start;
  piece.t1 = t_start + h;
  piece.t_ref = t_start;
  piece.h = h;
  piece.degree = ns;
  for (int k = 0; k <= ns; ++k) piece.c.col(k) = C.row(k).transpose();
  return piece;
}

/// Whether two modes put every contact in the same branch (open, stick, slip with the same sign
/// of the slip direction; a zero direction, a frictionless contact's closed mode, has no sign).
template <int NC>
bool same_branches(const Mode<NC>& a, const Mode<NC>& b) {
  for (int i = 0; i < NC; ++i) {
    if (a[i].mode != b[i].mode) return false;
    if (a[i].mode == ContactMode::Slip && a[i].slip_direction.dot(b[i].slip_direction) < 0.0) return false;
  }
  return true;
}

}  // namespace detail

/// The optimal input of x: the decision piecewise constant per element, right-continuous at
/// element boundaries, held outside [t0, T], through the OCP's input law when it has one (the law
/// is then evaluated at t). A law of time, except at the touchdowns, where it follows the mode
/// (reference spreading's extensions of the phases' inputs): a motion already in the stance's
/// mode before the touchdown's time gets the stance's first input, one still in the flight's
/// mode after it the flight's last. A touchdown's guard (the gap) does not depend on the input,
/// so the input there has no say in when the event happens, and the post-impact mode is to be
/// selected with the post-impact phase's input: under the law of time a touchdown located a hair
/// before the reference's time would be resolved with the flight's input (the hopper's: the
/// stance's force 68 N under its own first input, -21 N under the flight's last: a bounce), and
/// a tracking controller's extension of the stance before its start would carry the flight's
/// input. At the other events (a release, a slip onset, a stop) the input stays a law of time:
/// its jump at the event's time may be what fires the event (RefinementOptions::
/// releases_at_input_jumps), and a plant late for it gets the next phase's input there.
template <Scene S, class Ocp>
InputLaw<S> refined_input_law(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                              std::vector<double>& element_times) {
  constexpr int nu = S::nu;
  struct Table {
    std::vector<double> t;                  // element starts
    std::vector<Eigen::VectorXd> decision;  // per element
    std::vector<int> phase;                 // per element
    std::vector<int> first, last;           // per phase: its first and last element
    std::vector<double> start;              // per phase, and the end time last
    std::vector<Mode<S::nc>> mode;          // per phase
    std::vector<bool> touchdown_after;      // per phase: the event that ends it closes a contact by an impact
  };
  auto table = std::make_shared<Table>();
  element_times.clear();
  for (int e = 0; e < nlp.element_count(); ++e) {
    const int p = nlp.phase_of(e);
    const double t0 = x[nlp.time_index(p)], t1 = x[nlp.time_index(p + 1)];
    table->t.push_back(nlp.element_start_time(e, t0, t1));
    table->decision.push_back(x.template segment<nu>(nlp.control_index(e)));
    table->phase.push_back(p);
  }
  for (int p = 0; p < nlp.phase_count(); ++p) {
    table->start.push_back(x[nlp.time_index(p)]);
    table->first.push_back(nlp.first_element(p));
    table->last.push_back(nlp.first_element(p) + nlp.elements_in(p) - 1);
    table->mode.push_back(nlp.schedule().phases[static_cast<std::size_t>(p)]);
    table->touchdown_after.push_back(p + 1 < nlp.phase_count() && nlp.schedule().events[static_cast<std::size_t>(p)].impact());
  }
  table->start.push_back(x[nlp.time_index(nlp.phase_count())]);
  element_times = table->t;
  element_times.push_back(table->start.back());
  return [table, ocp = nlp.ocp()](double t, const VecT<double, 2 * S::nq>&, const Mode<S::nc>& mode) {
    const Table& tb = *table;
    const auto it = std::upper_bound(tb.t.begin(), tb.t.end(), t);
    std::size_t k = it == tb.t.begin() ? 0 : static_cast<std::size_t>(it - tb.t.begin()) - 1;
    const int p = tb.phase[k], P = static_cast<int>(tb.mode.size());
    const auto in = [&](int q) { return detail::same_branches(mode, tb.mode[static_cast<std::size_t>(q)]); };
    const auto up = [](int q) { return static_cast<std::size_t>(q); };
    // Outside phase p's mode, the boundary nearer t decides (a stance between a touchdown and a
    // release has the same flight mode on both sides).
    const bool nearer_start = t - tb.start[up(p)] <= tb.start[up(p + 1)] - t;
    if (!in(p) && nearer_start && p > 0 && tb.touchdown_after[up(p - 1)] && in(p - 1))
      k = up(tb.last[up(p - 1)]);  // still in the flight after the touchdown's time
    else if (!in(p) && !nearer_start && p + 1 < P && tb.touchdown_after[up(p)] && in(p + 1))
      k = up(tb.first[up(p + 1)]);  // already in the stance before the touchdown's time
    const VecT<double, nu> d = tb.decision[k];
    if constexpr (HasInputLaw<Ocp, double, nu>) return VecT<double, nu>(ocp.template input<double>(t, d));
    else return d;
  };
}

/// Whether the refined event ev is a release at an input jump (Event::input_jump: a fixed-time
/// event for the jump gains): RefinementOptions::releases_at_input_jumps, and a released contact
/// still carries a normal force under the ending phase's last input, lambda_n(x-, u-) > 1e-6
/// max(1, the largest |lambda_n| there). A release whose force reached zero is a crossing.
template <Scene S, class Ocp>
bool released_by_input_jump(const S& scene, const ScheduleRefinementNlp<S, Ocp>& nlp, const HybridTrajectory<S>& traj,
                            const Event<S>& ev) {
  if (!nlp.options().releases_at_input_jumps || ev.impact()) return false;
  const auto u_minus = traj.input(std::nextafter(ev.t, -std::numeric_limits<double>::infinity()), ev.x_minus, ev.mode_before);
  FlowWorkspace<S> ws;
  evaluate_flow(scene, ev.mode_before, ev.x_minus, u_minus, ws);
  double scale = 1.0;
  for (int i = 0; i < S::nc; ++i) scale = std::max(scale, std::abs(ws.force[i].normal));
  for (const Guard& g : ev.guards())
    if (g.kind == GuardKind::Release && ws.force[g.contact].normal > 1e-6 * scale) return true;
  return false;
}

/// Assembles RefinementResult::trajectory from a solution x of nlp (refinement.hpp).
template <Scene S, class Ocp>
HybridTrajectory<S> refined_trajectory(const S& scene, const ScheduleRefinementNlp<S, Ocp>& nlp,
                                       const Eigen::VectorXd& x, std::vector<double>& element_times) {
  constexpr int nx = 2 * S::nq;
  const int ns = nlp.stages();
  HybridTrajectory<S> traj;
  traj.input = refined_input_law(nlp, x, element_times);
  traj.input_breakpoints = element_times;  // the input is constant on each element
  for (int p = 0; p < nlp.phase_count(); ++p) {
    Segment<S> seg;
    seg.mode = nlp.schedule().phases[static_cast<std::size_t>(p)];
    seg.t_begin = x[nlp.time_index(p)];
    seg.t_end = x[nlp.time_index(p + 1)];
    for (int e = nlp.first_element(p); e < nlp.first_element(p) + nlp.elements_in(p) && seg.t_end > seg.t_begin; ++e) {
      const double h = (seg.t_end - seg.t_begin) * nlp.element_length_fraction(e);
      std::vector<Vec<nx>> stages;
      for (int r = 0; r < ns; ++r) stages.push_back(x.template segment<nx>(nlp.stage_index(e, r)));
      const double t_start = nlp.element_start_time(e, seg.t_begin, seg.t_end);
      seg.x.append(detail::collocation_piece<nx>(t_start, h, nlp.tableau(), x.template segment<nx>(nlp.element_start_index(e)), stages));
    }
    traj.segments.push_back(std::move(seg));
    if (p + 1 == nlp.phase_count()) break;
    Event<S> ev;
    ev.t = x[nlp.time_index(p + 1)];
    ev.x_minus = x.template segment<nx>(nlp.phase_end_index(p));
    ev.x_plus = x.template segment<nx>(nlp.start_index(p + 1));
    ev.mode_before = nlp.schedule().phases[static_cast<std::size_t>(p)];
    ev.mode_after = nlp.schedule().phases[static_cast<std::size_t>(p + 1)];
    Transition<S> tr;
    const ScheduleEvent& se = nlp.schedule().events[static_cast<std::size_t>(p)];
    tr.guards = se.guards;
    tr.mode_before = ev.mode_before;
    tr.mode_after = ev.mode_after;
    tr.x_before = ev.x_minus;
    tr.x_after = ev.x_plus;
    tr.impact = se.impact();
    if (tr.impact) {
      tr.impulse_mode = impulse_mode_after(scene, ev.mode_after);
      tr.impulse = nlp.impulses(x, p);
    }
    ev.transitions.push_back(tr);
    ev.input_jump = released_by_input_jump(scene, nlp, traj, ev);
    traj.events.push_back(std::move(ev));
  }
  traj.set_final_state(x.template segment<nx>(nlp.phase_end_index(nlp.phase_count() - 1)));
  traj.status = SimulationStatus::Completed;
  return traj;
}

}  // namespace saltus::timefreezing
