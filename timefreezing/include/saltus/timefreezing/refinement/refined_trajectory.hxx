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

}  // namespace detail

/// The optimal input of x as a law of time: the decision piecewise constant per element,
/// right-continuous at element boundaries, held outside [t0, T], through the OCP's input law when it
/// has one (the law is then evaluated at t). A law of time at the touchdowns too, whatever the
/// mode it is asked in: the analysis's first order (the jump gains with the input jumping at the
/// event's time) is the law of time's; an input that followed the mode there (the stance's first
/// input in the stance's mode before the touchdown's time, the flight's last after it) moved three
/// of the plank-box flagship's 100 Monte Carlo runs 5-10 % off the first order, where the law of
/// time keeps all within 0.9 % (docs/refinement.md, "Plank-box"). The per-phase re-simulation gives
/// the plant the stance's input at an early touchdown on its own (boundary_input_law).
template <Scene S, class Ocp>
InputLaw<S> refined_input_law(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                              std::vector<double>& element_times) {
  constexpr int nu = S::nu;
  struct Table {
    std::vector<double> t;                  // element starts
    std::vector<Eigen::VectorXd> decision;  // per element
  };
  auto table = std::make_shared<Table>();
  element_times.clear();
  for (int e = 0; e < nlp.element_count(); ++e) {
    const int p = nlp.phase_of(e);
    const double t0 = x[nlp.time_index(p)], t1 = x[nlp.time_index(p + 1)];
    table->t.push_back(nlp.element_start_time(e, t0, t1));
    table->decision.push_back(x.template segment<nu>(nlp.control_index(e)));
  }
  element_times = table->t;
  element_times.push_back(x[nlp.time_index(nlp.phase_count())]);
  return [table, ocp = nlp.ocp()](double t, const VecT<double, 2 * S::nq>&, const Mode<S::nc>&) {
    const auto it = std::upper_bound(table->t.begin(), table->t.end(), t);
    const std::size_t k = it == table->t.begin() ? 0 : static_cast<std::size_t>(it - table->t.begin()) - 1;
    const VecT<double, nu> d = table->decision[k];
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
