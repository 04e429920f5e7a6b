// The rows of the refinement NLP: which are implied, their layout and bounds, the structures, the
// initial point, names, and the readings of a solution.
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_build.hxx>

namespace saltus::timefreezing {

namespace detail {

/// The q-gradients of the equality path rows among `rows` that depend on q alone (their v and u
/// parts below tol of their norm), from a stage block's Jacobian J (rows: outputs, columns: w).
template <class Jacobian>
Eigen::MatrixXd holonomic_path_gradients(const Jacobian& J, const std::vector<int>& rows, const Eigen::VectorXd& lower,
                                         const Eigen::VectorXd& upper, int first_output, int nq, int nu, double tol) {
  Eigen::MatrixXd G(0, nq);
  for (int k : rows) {
    if (lower[k] != upper[k]) continue;
    const Eigen::VectorXd grad = J.row(first_output + k).head(2 * nq + nu).transpose();
    if (grad.tail(nq + nu).norm() <= tol * grad.norm()) append_row(G, grad.head(nq));
  }
  return G;
}

}  // namespace detail

/// (a) implied path rows, (c) implied gap rows of open contacts, phase by phase (file comment).
template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::find_implied_phase_rows() {
  const int P = phase_count();
  const double tol = options_.implied_row_tolerance;
  Eigen::VectorXd lower = Eigen::VectorXd::Zero(np), upper = Eigen::VectorXd::Zero(np);
  if constexpr (np > 0) {
    lower = ocp_.path_lower();
    upper = ocp_.path_upper();
  }
  FlowWorkspace<S, detail::Ad1<nw>> ws;
  VecT<double, stage_outputs> value;
  MatT<double, stage_outputs, nw> J;
  phase_path_rows_.assign(static_cast<std::size_t>(P), {});
  phase_validity_rows_.assign(static_cast<std::size_t>(P), {});
  std::array<int, nc> alone;
  alone.fill(-1);
  friction_leader_.assign(static_cast<std::size_t>(P), alone);  // no groups until find_friction_groups
  for (int p = 0; p < P; ++p) {
    const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
    const int e = first_element(p) + elements_in(p) / 2;
    detail::local_jacobian<nw, stage_outputs>([&](const auto& w) { return stage_block(e, point_theta(e, 0), w, ws); },
                                              point_local(guess_x_, e, 0), value, J);
    Kinematics<S, double> kin;
    const VecT<double, nx> xm = guess_x_.template segment<nx>(stage_index(e, 0));
    evaluate_kinematics<S, double>(scene_, VecT<double, nq>(xm.template head<nq>()), VecT<double, nq>(xm.template tail<nq>()), kin);
    Eigen::MatrixXd closed(0, nq);
    for (int i = 0; i < nc; ++i)
      if (mode[i].closed()) detail::append_row(closed, kin.contacts[i].wn);
    for (int k = 0; k < np; ++k) {
      const Eigen::VectorXd grad = J.row(nx + 1 + max_validity + k).head(nx + nu).transpose();
      const double residual = std::max(grad.tail(nq + nu).norm() / std::max(grad.norm(), 1e-300),
                                        detail::span_residual(closed, grad.head(nq)));
      if (closed.rows() > 0 && lower[k] == upper[k] && grad.norm() > 0.0 && residual <= tol) {
        implied_.push_back({p, -1, k, "path row " + std::to_string(k) + " in phase " + std::to_string(p), residual});
        continue;
      }
      phase_path_rows_[static_cast<std::size_t>(p)].push_back(k);
    }
    find_friction_groups(p, kin);
    // (c): an open contact's gap held at zero by the closed contacts and the imposed holonomic path rows.
    Eigen::MatrixXd locks = closed;
    const Eigen::MatrixXd path = detail::holonomic_path_gradients(J, imposed_path_rows(p), lower, upper,
                                                                  nx + 1 + max_validity, nq, nu, tol);
    for (int r = 0; r < path.rows(); ++r) detail::append_row(locks, path.row(r).transpose());
    for (int i = 0, k = 0; i < nc; ++i) {
      const int count = count_validity_of(mode, i);
      const int leader = friction_leader_[static_cast<std::size_t>(p)][static_cast<std::size_t>(i)];
      for (int c = 0; c < count; ++c, ++k) {
        if (c > 0 && leader >= 0 && leader != i) {  // (d): a group member's friction rows
          implied_.push_back({p, -1, k, "friction row of " + scene_.contact(i).name + " in phase " + std::to_string(p) +
                                            " (grouped with " + scene_.contact(leader).name + ")", 0.0});
          continue;
        }
        if (!mode[i].closed() && locks.rows() > 0) {
          const double residual = detail::span_residual(locks, kin.contacts[i].wn);
          if (residual <= tol) {
            implied_.push_back({p, -1, k, "gap of open contact " + scene_.contact(i).name + " in phase " + std::to_string(p) +
                                              " (held at 0)", residual});
            continue;
          }
        }
        phase_validity_rows_[static_cast<std::size_t>(p)].interior.push_back(k);
      }
    }
  }
}

/// (d) the friction groups of phase p from the contact kinematics at its guess (file comment).
template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::find_friction_groups(int p, const Kinematics<S, double>& kin) {
  const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
  std::array<int, nc> leader;
  leader.fill(-1);
  for (int j = 0; j < nc; ++j) {
    if (!mode[j].closed() || scene_.contact(j).tangents() == 0) continue;
    leader[static_cast<std::size_t>(j)] = j;
    const Eigen::VectorXd wj = kin.contacts[j].Wt.col(0);
    for (int i = 0; i < j; ++i) {
      if (leader[static_cast<std::size_t>(i)] != i || !(mode[i] == mode[j])) continue;
      Eigen::MatrixXd wi(1, nq);
      wi.row(0) = kin.contacts[i].Wt.col(0).transpose();
      if (detail::span_residual(wi, wj) <= options_.implied_row_tolerance) {
        leader[static_cast<std::size_t>(j)] = i;
        break;
      }
    }
  }
  friction_leader_[static_cast<std::size_t>(p)] = leader;
}

/// EVENT ENDS (refinement_nlp.hpp): the validity values dropped at the phases' first and last points.
template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::restrict_event_ends() {
  const int P = phase_count();
  // value index of contact i's entries in mode m: [first, first + count)
  const auto entries = [&](const Mode<nc>& m, int i) {
    int first = 0;
    for (int j = 0; j < i; ++j) first += count_validity_of(m, j);
    return std::pair<int, int>(first, first + count_validity_of(m, i));
  };
  const auto drop = [](std::vector<int>& list, int from, int to) {
    list.erase(std::remove_if(list.begin(), list.end(), [&](int k) { return k >= from && k < to; }), list.end());
  };
  for (int p = 0; p < P; ++p) {
    PhaseValidity& v = phase_validity_rows_[static_cast<std::size_t>(p)];
    v.at_start = v.at_end = v.interior;
    const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
    for (int i = 0; i < nc; ++i) {
      const auto [first, last] = entries(mode, i);
      const bool frictional = scene_.contact(i).tangents() > 0;
      if (p == 0 && !mode[i].closed()) drop(v.at_start, first, last);  // gap(x0): no variable moves it
      if (p > 0) {
        const ScheduleEvent& before = schedule_.events[static_cast<std::size_t>(p - 1)];
        const bool thrown_off = before.impact() && !mode[i].closed() && schedule_.phases[static_cast<std::size_t>(p - 1)][i].closed();
        if (thrown_off) drop(v.at_start, first, last);  // a release keeps the row: RELEASE CONSISTENCY
        if ((before.has(i, GuardKind::SlipOnset) || (before.impact() && mode[i].closed())) && frictional &&
            mode[i].mode == ContactMode::Slip)
          drop(v.at_start, first + 1, last);  // the slip sign
      }
      if (p + 1 < P) {
        const ScheduleEvent& after = schedule_.events[static_cast<std::size_t>(p)];
        const bool released_by_guard = after.has(i, GuardKind::Release) && !options_.releases_at_input_jumps;
        // A release replaces lambda_n >= 0 and a stick's cone (0 >= 0 at lambda_n = 0); a slide's sign
        // row stays (RefinementOptions::slip_speed_margin holds up to the release).
        const bool slide = mode[i].closed() && mode[i].mode == ContactMode::Slip;
        if (after.has(i, GuardKind::Touchdown)) drop(v.at_end, first, last);
        else if (released_by_guard) drop(v.at_end, first, slide ? first + 1 : last);
        if ((after.has(i, GuardKind::Stop) || after.has(i, GuardKind::SlipOnset)) && frictional) drop(v.at_end, first + 1, last);
      }
    }
  }
}

/// (b) implied guards, event by event (file comment); also the event rows' layout.
template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::find_implied_guards() {
  const int P = phase_count();
  const double tol = options_.implied_row_tolerance;
  Eigen::VectorXd lower = Eigen::VectorXd::Zero(np), upper = Eigen::VectorXd::Zero(np);
  if constexpr (np > 0) {
    lower = ocp_.path_lower();
    upper = ocp_.path_upper();
  }
  FlowWorkspace<S, detail::Ad1<nw>> ws;
  FlowWorkspace<S, detail::Ad1<nwe>> fws;
  JumpWorkspace<S, detail::Ad1<nwe>> jws;
  VecT<double, stage_outputs> value;
  MatT<double, stage_outputs, nw> J;
  events_.assign(static_cast<std::size_t>(std::max(P - 1, 0)), EventRows{});
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
    const int last = first_element(b) + elements_in(b) - 1, r_last = tableau_.stages - 1;
    detail::local_jacobian<nw, stage_outputs>([&](const auto& w) { return stage_block(last, point_theta(last, r_last), w, ws); },
                                              point_local(guess_x_, last, r_last), value, J);
    for (int k : imposed_path_rows(b))
      if (lower[k] == upper[k]) detail::append_row(K, J.row(nx + 1 + max_validity + k).head(nx + nu).transpose());
    // The gaps of the contacts closed in the ending phase hold at x- too (by its start and its flow).
    Kinematics<S, double> kin;
    const VecT<double, nx> xm = guess_x_.template segment<nx>(phase_end_index(b));
    evaluate_kinematics<S, double>(scene_, VecT<double, nq>(xm.template head<nq>()), VecT<double, nq>(xm.template tail<nq>()), kin);
    for (int i = 0; i < nc; ++i)
      if (before[i].closed()) {
        Eigen::VectorXd row = Eigen::VectorXd::Zero(nx + nu);
        row.head(nq) = kin.contacts[i].wn;
        detail::append_row(K, row);
      }
    // RELEASE AT AN INPUT JUMP: the release guards are not rows; the stance's validity rows at x-
    // and the flight's h_n'' >= 0 at its start make the release.
    std::vector<Guard> guards = se.guards;
    if (options_.releases_at_input_jumps)
      std::erase_if(guards, [](const Guard& g) { return g.kind == GuardKind::Release; });
    ev.imposed_guards = guards;
    for (const Guard& g : guards)
      if (g.kind == GuardKind::Release && before[g.contact].mode == ContactMode::Stick && scene_.contact(g.contact).tangents() > 0)
        ev.released_sticking.push_back(g.contact);
    VecT<double, event_outputs> ev_value;
    MatT<double, event_outputs, nwe> ev_jacobian;
    detail::local_jacobian<nwe, event_outputs>([&](const auto& w) { return event_block(b, w, fws, jws); },
                                               event_local(guess_x_, b), ev_value, ev_jacobian);
    std::vector<Guard> kept;
    for (std::size_t k = 0; k < guards.size(); ++k) {
      const Eigen::VectorXd grad = ev_jacobian.row(static_cast<int>(k)).head(nx + nu).transpose();
      const double residual = detail::span_residual(K, grad);
      if (grad.norm() > 0.0 && residual <= tol) {
        implied_.push_back({-1, b, static_cast<int>(k),
                            std::string(to_string(guards[k].kind)) + " " + scene_.contact(guards[k].contact).name +
                                " at event " + std::to_string(b),
                            residual});
        continue;
      }
      kept.push_back(guards[k]);
      detail::append_row(K, grad);
    }
    ev.imposed_guards = kept;
  }
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::build_rows() {
  const int P = phase_count(), ns = tableau_.stages;
  int row = 0;
  point_row_.assign(static_cast<std::size_t>(element_count() * (ns + 1)), 0);
  for (int e = 0; e < element_count(); ++e) {
    const int p = phase_of(e);
    const int npath = static_cast<int>(imposed_path_rows(p).size());
    for (int r = -1; r < ns; ++r) {
      point_row_[point_slot(e, r)] = row;
      const int nv = static_cast<int>(imposed_validity(e, r).size());
      row += r < 0 ? nv : nx + nv + npath;
    }
  }
  for (EventRows& ev : events_) {
    ev.first_row = row;
    row += ev.row_count();
  }
  duration_row_ = row;
  row += P;
  terminal_row_ = row;
  row += static_cast<int>(imposed_terminal_rows_.size());
  m_ = row;
  point_value_.assign(point_row_.size(), VecT<double, stage_outputs>::Zero());
  point_jacobian_.assign(point_row_.size(), MatT<double, stage_outputs, nw>::Zero());
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
    const int p = phase_of(e);
    const std::vector<int>& path = imposed_path_rows(p);
    for (int r = -1; r < ns; ++r) {
      const int row = point_row(e, r) + validity_offset_in_rows(r);
      const int nv = static_cast<int>(imposed_validity(e, r).size());
      g_upper.segment(row, nv).setConstant(inf);
      if (r < 0) continue;
      for (std::size_t k = 0; k < path.size(); ++k) {
        g_lower[row + nv + static_cast<int>(k)] = lo[path[k]];
        g_upper[row + nv + static_cast<int>(k)] = hi[path[k]];
      }
    }
  }
  for (const EventRows& ev : events_) {
    const int approach = ev.first_row + static_cast<int>(ev.imposed_guards.size() + ev.released_sticking.size());
    g_lower.segment(approach, static_cast<int>(ev.approach_contacts.size())).setConstant(-inf);
    g_upper.segment(approach, static_cast<int>(ev.approach_contacts.size())).setConstant(-options_.touchdown_speed);
    const int signs = approach + static_cast<int>(ev.approach_contacts.size()) + nx;
    g_upper.segment(signs, ev.impulse_rows + static_cast<int>(ev.separating_contacts.size())).setConstant(inf);
  }
  g_lower.segment(duration_row_, P).setConstant(options_.min_phase_duration);
  g_upper.segment(duration_row_, P).setConstant(inf);
  if constexpr (nt > 0) {
    const VecT<double, nt> lo = ocp_.terminal_lower(), hi = ocp_.terminal_upper();
    for (std::size_t j = 0; j < imposed_terminal_rows_.size(); ++j) {
      g_lower[terminal_row_ + static_cast<int>(j)] = lo[imposed_terminal_rows_[j]];
      g_upper[terminal_row_ + static_cast<int>(j)] = hi[imposed_terminal_rows_[j]];
    }
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
  if (j >= 0 && j < first_event_row) {  // a point's rows: the last point whose first row is <= j
    const auto it = std::upper_bound(point_row_.begin(), point_row_.end(), j) - 1;
    const int slot = static_cast<int>(it - point_row_.begin()), e = slot / (ns + 1), r = slot % (ns + 1) - 1;
    const int p = phase_of(e), nv = static_cast<int>(imposed_validity(e, r).size());
    int o = j - *it;
    const std::string where = "[phase " + std::to_string(p) + ", element " + std::to_string(e - first_element(p)) +
                              (r < 0 ? std::string(", start") : ", stage " + std::to_string(r)) + "]";
    if (r >= 0 && o < nx) return "collocation" + where + "[" + std::to_string(o) + "]";
    o -= validity_offset_in_rows(r);
    if (o < nv) return "mode validity" + where + "[" + std::to_string(imposed_validity(e, r)[static_cast<std::size_t>(o)]) + "]";
    return "path" + where + "[" + std::to_string(imposed_path_rows(p)[static_cast<std::size_t>(o - nv)]) + "]";
  }
  for (std::size_t b = 0; b < events_.size(); ++b)
    if (j >= events_[b].first_row && j < events_[b].first_row + events_[b].row_count())
      return "event " + std::to_string(b) + " (" + describe_event(scene_, schedule_.events[b]) + ")[" +
             std::to_string(j - events_[b].first_row) + "]";
  if (j >= duration_row_ && j < duration_row_ + phase_count()) return "duration of phase " + std::to_string(j - duration_row_);
  if (j >= terminal_row_ && j < terminal_row_ + static_cast<int>(imposed_terminal_rows_.size()))
    return "terminal[" + std::to_string(imposed_terminal_rows_[static_cast<std::size_t>(j - terminal_row_)]) + "]";
  return Mpcc::constraint_name(j);
}

}  // namespace saltus::timefreezing

#include <saltus/timefreezing/refinement/refinement_nlp_terminal.hxx>
#include <saltus/timefreezing/refinement/refinement_nlp_reading.hxx>
#include <saltus/timefreezing/refinement/refinement_nlp_warm_start.hxx>
