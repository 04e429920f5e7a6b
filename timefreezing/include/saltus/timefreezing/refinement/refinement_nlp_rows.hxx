// The rows of the refinement NLP: which are implied, their layout and bounds, the structures, the
// initial point, names, and the readings of a solution.
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_build.hxx>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::find_implied_rows(const ScheduleGuess<S>& guess) {
  (void)guess;
  const int P = phase_count();
  const double tol = options_.implied_row_tolerance;
  phase_path_rows_.assign(static_cast<std::size_t>(P), {});
  VecT<double, np> path_lower, path_upper;
  if constexpr (np > 0) {
    path_lower = ocp_.path_lower();
    path_upper = ocp_.path_upper();
  }
  FlowWorkspace<S, detail::Ad1<nw>> ws;
  VecT<double, stage_outputs> value;
  MatT<double, stage_outputs, nw> J;
  const auto stage_jacobian_at = [&](int e, int r) {
    detail::local_jacobian<nw, stage_outputs>([&](const auto& w) { return stage_block(phase_of(e), stage_theta(e, r), w, ws); },
                                              stage_local(guess_x_, e, r), value, J);
  };
  for (int p = 0; p < P; ++p) {
    const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
    const int e = first_element(p) + elements_in(p) / 2;
    Eigen::MatrixXd G(0, nq);
    if (np > 0 && mode.closed_count() > 0) {
      stage_jacobian_at(e, 0);
      Kinematics<S, double> kin;
      const VecT<double, nx> xm = guess_x_.template segment<nx>(stage_index(e, 0));
      evaluate_kinematics<S, double>(scene_, VecT<double, nq>(xm.template head<nq>()), VecT<double, nq>(xm.template tail<nq>()), kin);
      for (int i = 0; i < nc; ++i)
        if (mode[i].closed()) detail::append_row(G, kin.contacts[i].wn);
    }
    for (int k = 0; k < np; ++k) {
      if (G.rows() > 0 && path_lower[k] == path_upper[k]) {
        const Eigen::VectorXd grad = J.row(nx + 1 + max_validity + k).head(nx + nu).transpose();
        const double rest = grad.tail(nq + nu).norm();
        const double residual = std::max(rest / std::max(grad.norm(), 1e-300), detail::span_residual(G, grad.head(nq)));
        if (grad.norm() > 0.0 && residual <= tol) {
          implied_.push_back({p, -1, k, "path row " + std::to_string(k) + " in phase " + std::to_string(p), residual});
          continue;
        }
      }
      phase_path_rows_[static_cast<std::size_t>(p)].push_back(k);
    }
  }
  events_.assign(static_cast<std::size_t>(std::max(P - 1, 0)), EventRows{});
  FlowWorkspace<S, detail::Ad1<nwe>> fws;
  JumpWorkspace<S, detail::Ad1<nwe>> jws;
  for (int b = 0; b + 1 < P; ++b) {
    EventRows& ev = events_[static_cast<std::size_t>(b)];
    const ScheduleEvent& se = schedule_.events[static_cast<std::size_t>(b)];
    const Mode<nc>& before = schedule_.phases[static_cast<std::size_t>(b)];
    const Mode<nc>& after = schedule_.phases[static_cast<std::size_t>(b + 1)];
    ev.impact = se.impact();
    if (ev.impact) {
      ev.impulse_mode = impulse_mode_after(scene_, after);
      for (const Guard& g : se.guards)
        if (g.kind == GuardKind::Touchdown) ev.approach_contacts.push_back(g.contact);
      for (int i = 0; i < nc; ++i)
        if (before[i].closed() && !after[i].closed()) ev.separating_contacts.push_back(i);
    }
    ev.impulse_rows = ev.impact ? count_impulse_rows(ev) : 0;
    // The equality rows at x-: the imposed equality path rows of the ending phase, then the guards.
    Eigen::MatrixXd K(0, nx + nu);
    const int last = first_element(b) + elements_in(b) - 1;
    if (np > 0) stage_jacobian_at(last, tableau_.stages - 1);
    for (int k : imposed_path_rows(b))
      if (path_lower[k] == path_upper[k]) detail::append_row(K, J.row(nx + 1 + max_validity + k).head(nx + nu).transpose());
    ev.imposed_guards = se.guards;
    VecT<double, event_outputs> ev_value;
    MatT<double, event_outputs, nwe> ev_jacobian;
    detail::local_jacobian<nwe, event_outputs>([&](const auto& w) { return event_block(b, w, fws, jws); },
                                               event_local(guess_x_, b), ev_value, ev_jacobian);
    std::vector<Guard> kept;
    for (std::size_t k = 0; k < se.guards.size(); ++k) {
      const Eigen::VectorXd grad = ev_jacobian.row(static_cast<int>(k)).head(nx + nu).transpose();
      const double residual = detail::span_residual(K, grad);
      if (grad.norm() > 0.0 && residual <= tol) {
        implied_.push_back({-1, b, static_cast<int>(k),
                            std::string(to_string(se.guards[k].kind)) + " " + scene_.contact(se.guards[k].contact).name +
                                " at event " + std::to_string(b),
                            residual});
        continue;
      }
      kept.push_back(se.guards[k]);
      detail::append_row(K, grad);
    }
    ev.imposed_guards = kept;
  }
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::build_rows() {
  const int P = phase_count(), ns = tableau_.stages;
  int row = 0;
  stage_row_.assign(static_cast<std::size_t>(element_count() * ns), 0);
  for (int e = 0; e < element_count(); ++e)
    for (int r = 0; r < ns; ++r) {
      stage_row_[static_cast<std::size_t>(e * ns + r)] = row;
      row += nx + validity_count(phase_of(e)) + static_cast<int>(imposed_path_rows(phase_of(e)).size());
    }
  for (EventRows& ev : events_) {
    ev.first_row = row;
    row += ev.row_count();
  }
  duration_row_ = row;
  row += P;
  terminal_row_ = row;
  row += nt;
  m_ = row;
  stage_value_.assign(static_cast<std::size_t>(element_count() * ns), VecT<double, stage_outputs>::Zero());
  stage_jacobian_.assign(stage_value_.size(), MatT<double, stage_outputs, nw>::Zero());
  event_value_.assign(events_.size(), VecT<double, event_outputs>::Zero());
  event_jacobian_.assign(events_.size(), MatT<double, event_outputs, nwe>::Zero());
  terminal_value_.setZero();
  terminal_jacobian_.setZero();
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::build_structures() {
  jacobian_structure_.clear();
  walk_jacobian([&](int row, int col, double) { jacobian_structure_.push_back({row, col}); });
  hessian_structure_.clear();
  const Eigen::VectorXd none;
  walk_hessian(guess_x_, 0.0, none, [&](int row, int col, double) { hessian_structure_.push_back({row, col}); });
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::bounds(Eigen::Ref<Eigen::VectorXd> x_lower, Eigen::Ref<Eigen::VectorXd> x_upper,
                                           Eigen::Ref<Eigen::VectorXd> g_lower,
                                           Eigen::Ref<Eigen::VectorXd> g_upper) const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const int P = phase_count(), ns = tableau_.stages;
  x_lower.setConstant(-inf);
  x_upper.setConstant(inf);
  x_lower.head(P + 1).setConstant(horizon_.initial_time);
  x_upper.head(P + 1).setConstant(horizon_.final_time);
  x_upper[time_index(0)] = horizon_.initial_time;
  x_lower[time_index(P)] = horizon_.final_time;
  x_lower.template segment<nx>(start_index(0)) = horizon_.x0;
  x_upper.template segment<nx>(start_index(0)) = horizon_.x0;
  for (int e = 0; e < element_count(); ++e) {
    if (horizon_.control_lower.size() == nu) x_lower.template segment<nu>(control_index(e)) = horizon_.control_lower;
    if (horizon_.control_upper.size() == nu) x_upper.template segment<nu>(control_index(e)) = horizon_.control_upper;
  }
  g_lower.setZero();
  g_upper.setZero();
  VecT<double, np> lo, hi;
  if constexpr (np > 0) {
    lo = ocp_.path_lower();
    hi = ocp_.path_upper();
  }
  for (int e = 0; e < element_count(); ++e) {
    const int p = phase_of(e), nv = validity_count(p);
    const std::vector<int>& path = imposed_path_rows(p);
    for (int r = 0; r < ns; ++r) {
      const int row = stage_row(e, r) + nx;
      g_upper.segment(row, nv).setConstant(inf);
      for (std::size_t k = 0; k < path.size(); ++k) {
        g_lower[row + nv + static_cast<int>(k)] = lo[path[k]];
        g_upper[row + nv + static_cast<int>(k)] = hi[path[k]];
      }
    }
  }
  for (const EventRows& ev : events_) {
    const int approach = ev.first_row + static_cast<int>(ev.imposed_guards.size());
    g_lower.segment(approach, static_cast<int>(ev.approach_contacts.size())).setConstant(-inf);
    const int signs = approach + static_cast<int>(ev.approach_contacts.size()) + nx;
    g_upper.segment(signs, ev.impulse_rows + static_cast<int>(ev.separating_contacts.size())).setConstant(inf);
  }
  g_lower.segment(duration_row_, P).setConstant(options_.min_phase_duration);
  g_upper.segment(duration_row_, P).setConstant(inf);
  if constexpr (nt > 0) {
    g_lower.template segment<nt>(terminal_row_) = ocp_.terminal_lower();
    g_upper.template segment<nt>(terminal_row_) = ocp_.terminal_upper();
  }
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::initial_point(Eigen::Ref<Eigen::VectorXd> x) const {
  x = guess_x_;
}

template <Scene S, class Ocp>
std::string ScheduleRefinementNlp<S, Ocp>::variable_name(int i) const {
  const int P = phase_count();
  if (i <= P) return "t_" + std::to_string(i);
  if (i < element_base_) return "X_phase" + std::to_string((i - P - 1) / nx) + "[" + std::to_string((i - P - 1) % nx) + "]";
  const int size = nu + tableau_.stages * nx, e = (i - element_base_) / size, o = (i - element_base_) % size;
  const std::string where = "[phase " + std::to_string(phase_of(e)) + ", element " + std::to_string(e - first_element(phase_of(e)));
  if (o < nu) return "u" + where + "][" + std::to_string(o) + "]";
  return "X" + where + ", stage " + std::to_string((o - nu) / nx) + "][" + std::to_string((o - nu) % nx) + "]";
}

template <Scene S, class Ocp>
std::string ScheduleRefinementNlp<S, Ocp>::constraint_name(int j) const {
  const int ns = tableau_.stages;
  const int first_event_row = events_.empty() ? duration_row_ : events_.front().first_row;
  if (j >= 0 && j < first_event_row) {  // a stage point's rows: the last stage whose first row is <= j
    const auto it = std::upper_bound(stage_row_.begin(), stage_row_.end(), j) - 1;
    const int k = static_cast<int>(it - stage_row_.begin()), e = k / ns, r = k % ns, p = phase_of(e);
    const int o = j - *it, nv = validity_count(p);
    const std::string where = "[phase " + std::to_string(p) + ", element " + std::to_string(e - first_element(p)) +
                              ", stage " + std::to_string(r) + "]";
    if (o < nx) return "collocation" + where + "[" + std::to_string(o) + "]";
    if (o < nx + nv) return "mode validity" + where + "[" + std::to_string(o - nx) + "]";
    return "path" + where + "[" + std::to_string(imposed_path_rows(p)[static_cast<std::size_t>(o - nx - nv)]) + "]";
  }
  for (std::size_t b = 0; b < events_.size(); ++b)
    if (j >= events_[b].first_row && j < events_[b].first_row + events_[b].row_count())
      return "event " + std::to_string(b) + " (" + describe_event(scene_, schedule_.events[b]) + ")[" +
             std::to_string(j - events_[b].first_row) + "]";
  if (j >= duration_row_ && j < duration_row_ + phase_count()) return "duration of phase " + std::to_string(j - duration_row_);
  if (j >= terminal_row_ && j < terminal_row_ + nt) return "terminal[" + std::to_string(j - terminal_row_) + "]";
  return Mpcc::constraint_name(j);
}

}  // namespace saltus::timefreezing

#include <saltus/timefreezing/refinement/refinement_nlp_reading.hxx>
