// Schedule edits (refinement.hpp, "SCHEDULE EDITS"): read a solution's multipliers and durations,
// propose one edit, and build the edited schedule's guess from the refined trajectory.
#pragma once

#include <saltus/timefreezing/refinement/refined_trajectory.hxx>

#include <cmath>
#include <memory>
#include <optional>
#include <tuple>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

namespace detail {

/// The position of contact i's first validity value in a mode's list (refinement_nlp.hpp order).
template <Scene S>
int validity_offset(const S& scene, const Mode<S::nc>& mode, int contact) {
  int k = 0;
  for (int i = 0; i < contact; ++i) {
    if (!mode[i].closed()) ++k;
    else k += 1 + (scene.contact(i).tangents() == 0 ? 0 : (mode[i].mode == ContactMode::Stick ? 2 : 1));
  }
  return k;
}

/// The edit that an active validity value k of contact i asks for (its value index within the
/// contact's entries: 0 gap or lambda_n; stick: 1 mu lambda_n - lambda_t, 2 mu lambda_n + lambda_t;
/// slip: 1 s zeta_t).
inline std::string edit_kind(const ContactState& c, int entry) {
  if (!c.closed()) return "touch";
  if (entry == 0) return "lift-off";
  if (c.mode == ContactMode::Slip) return "stick";
  return entry == 1 ? "slip-" : "slip+";  // lambda_t at +mu lambda_n: the friction pushes +, the slip goes -
}

/// The time of stage point (element e, point r) of phase p: r = -1 the element's start.
template <Scene S, class Ocp>
double stage_point_time(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x, int p, int e, int r) {
  const double t0 = x[nlp.time_index(p)], t1 = x[nlp.time_index(p + 1)];
  (void)p;
  return t0 + (t1 - t0) * nlp.point_theta(e, r);
}

/// The active arc of validity value k in phase p around time t: the first and last stage point of
/// the run of consecutive points (in time order) whose row has a multiplier >= multiplier_threshold
/// (Ipopt's active set: an inactive row's multiplier is about mu / slack, far below it) and that
/// contains t. An edit then changes the mode over the whole arc, not around its strongest point.
template <Scene S, class Ocp>
std::pair<double, double> active_arc(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                                     const Eigen::VectorXd& lambda, int p, int k, double t, double multiplier_threshold) {
  std::vector<std::pair<double, bool>> points;  // (time, active), in time order
  for (int e = nlp.first_element(p); e < nlp.first_element(p) + nlp.elements_in(p); ++e)
    for (int r = -1; r < nlp.stages(); ++r) {
      const int row = nlp.validity_row(e, r, k);
      points.emplace_back(stage_point_time(nlp, x, p, e, r), row >= 0 && -lambda[row] >= multiplier_threshold);
    }
  std::pair<double, double> arc{t, t};
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (points[i].first != t || !points[i].second) continue;
    std::size_t a = i, b = i;
    while (a > 0 && points[a - 1].second) --a;
    while (b + 1 < points.size() && points[b + 1].second) ++b;
    arc = {points[a].first, points[b].first};
    break;
  }
  return arc;
}

/// The largest active validity row with a positive multiplier at a point inside its phase (not the
/// phase's first or last point), with the active arc it belongs to.
template <Scene S, class Ocp>
std::optional<ScheduleEdit> strongest_validity_edit(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                                                    const Eigen::VectorXd& lambda, const RefinementEdits& o) {
  std::optional<ScheduleEdit> best;
  int best_k = -1;
  const int ns = nlp.stages();
  for (int e = 0; e < nlp.element_count(); ++e) {
    const int p = nlp.phase_of(e);
    const Mode<S::nc>& mode = nlp.schedule().phases[static_cast<std::size_t>(p)];
    const bool first_element = e == nlp.first_element(p), last_element = e + 1 == nlp.first_element(p) + nlp.elements_in(p);
    for (int r = first_element ? 0 : -1; r < ns - (last_element ? 1 : 0); ++r) {
      const std::vector<double> v = nlp.validity_values(x, e, r);
      for (int i = 0, first = 0; i < S::nc; first += nlp.count_validity_of(mode, i), ++i)
        for (int entry = 0; entry < nlp.count_validity_of(mode, i); ++entry) {
          const int k = first + entry, row = nlp.validity_row(e, r, k);
          if (row < 0) continue;  // implied, not a row
          const double multiplier = -lambda[row];  // Ipopt: lambda <= 0 on an active lower bound
          if (v[static_cast<std::size_t>(k)] > o.active_tolerance || multiplier < o.multiplier_threshold) continue;
          if (best && multiplier <= best->multiplier) continue;
          ScheduleEdit edit;
          edit.kind = edit_kind(mode[i], entry);
          edit.phase = p;
          edit.contact = i;
          edit.t = stage_point_time(nlp, x, p, e, r);
          edit.multiplier = multiplier;
          best = edit;
          best_k = k;
        }
    }
  }
  if (best) std::tie(best->t_begin, best->t_end) = active_arc(nlp, x, lambda, best->phase, best_k, best->t, o.multiplier_threshold);
  return best;
}

}  // namespace detail

/// The edit the solution x (with constraint multipliers lambda) asks for, or none: a vanishing phase
/// first, then the strongest active validity row (refinement.hpp).
template <Scene S, class Ocp>
std::optional<ScheduleEdit> propose_edit(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                                         const Eigen::VectorXd& lambda, const RefinementEdits& options) {
  if (nlp.phase_count() > 1)
    for (int p = 0; p < nlp.phase_count(); ++p)
      if (x[nlp.time_index(p + 1)] - x[nlp.time_index(p)] <= options.vanishing_duration) {
        ScheduleEdit edit;
        edit.kind = "vanish";
        edit.phase = p;
        edit.t = edit.t_begin = edit.t_end = x[nlp.time_index(p)];
        return edit;
      }
  return detail::strongest_validity_edit(nlp, x, lambda, options);
}

/// The guess of the edited schedule: its phases (each with the phase of `traj` it is read from),
/// its event times, the refined trajectory as the motion. Returns nothing when the edit leaves an
/// invalid schedule (it is then not tried).
template <Scene S>
std::optional<ScheduleGuess<S>> edited_guess(const S& scene, const HybridTrajectory<S>& traj, const ModeSchedule<S::nc>& schedule,
                                             const ScheduleEdit& edit) {
  const int P = schedule.phase_count();
  std::vector<Mode<S::nc>> modes;
  std::vector<int> source;      // the old phase each new phase reads its guess from
  std::vector<double> starts;   // each new phase's start time
  const auto add = [&](const Mode<S::nc>& m, int old, double t) {
    modes.push_back(m);
    source.push_back(old);
    starts.push_back(t);
  };
  for (int p = 0; p < P; ++p) {
    const Mode<S::nc>& m = schedule.phases[static_cast<std::size_t>(p)];
    const double t0 = traj.segments[static_cast<std::size_t>(p)].t_begin, t1 = traj.segments[static_cast<std::size_t>(p)].t_end;
    if (p != edit.phase) {
      add(m, p, t0);
      continue;
    }
    if (edit.kind == "vanish") continue;
    Mode<S::nc> changed = m;
    if (edit.kind == "lift-off") {
      changed[edit.contact] = ContactState::open();
    } else if (edit.kind == "stick") {
      changed[edit.contact] = ContactState::stick();
    } else if (edit.kind == "slip+" || edit.kind == "slip-") {
      changed[edit.contact] = ContactState::slip_planar(edit.kind == "slip+" ? 1 : -1);
    } else {
      const VecT<double, 2 * S::nq> x = traj.state(p, edit.t);
      Kinematics<S, double> kin;
      evaluate_kinematics<S, double>(scene, VecT<double, S::nq>(x.template head<S::nq>()), VecT<double, S::nq>(x.template tail<S::nq>()), kin);
      const double zt = kin.contacts[edit.contact].zeta_t[0];
      changed[edit.contact] = std::abs(zt) <= 1e-7 ? ContactState::stick() : ContactState::slip_planar(zt > 0 ? 1 : -1);
    }
    // the changed mode over the active arc, at least `width` around the strongest point
    const double width = std::min(0.25 * (t1 - t0), 0.02);
    const double a = std::clamp(std::min(edit.t_begin, edit.t - 0.5 * width), t0, t1),
                 b = std::clamp(std::max(edit.t_end, edit.t + 0.5 * width), t0, t1);
    add(m, p, t0);
    add(changed, p, a);
    add(m, p, b);
  }
  ModeSchedule<S::nc> edited;
  ScheduleGuess<S> guess;
  std::vector<std::vector<int>> sources;  // per edited phase, the old phases it reads, in time order
  for (std::size_t k = 0; k < modes.size(); ++k) {
    if (k > 0 && guards_between(scene, edited.phases.back(), modes[k]).guards.empty()) {  // same mode: merge
      if (sources.back().back() != source[k]) sources.back().push_back(source[k]);
      continue;
    }
    if (k > 0) guess.event_times.push_back(starts[k]);
    edited.phases.push_back(modes[k]);
    sources.push_back({source[k]});
  }
  for (std::size_t k = 1; k < edited.phases.size(); ++k) {
    ScheduleEvent e = guards_between(scene, edited.phases[k - 1], edited.phases[k]);
    if (e.impact()) {  // at an impact the impulse decides the other contacts (extraction's rule 4)
      std::vector<Guard> touchdowns;
      for (const Guard& g : e.guards)
        if (g.kind == GuardKind::Touchdown) touchdowns.push_back(g);
      e.guards = touchdowns;
    }
    edited.events.push_back(e);
  }
  try {
    guess.schedule = validated(scene, edited);
  } catch (const InvalidArgument&) {
    return std::nullopt;
  }
  const auto shared = std::make_shared<const HybridTrajectory<S>>(traj);
  // A phase merged from several old ones (the neighbours of a vanished phase) reads, at t, the last
  // of them that has begun by t: the refined motion itself on both sides of the removed phase.
  guess.state = [shared, sources](int phase, double t) {
    const std::vector<int>& olds = sources[static_cast<std::size_t>(phase)];
    int old = olds.front();
    for (int o : olds)
      if (shared->segments[static_cast<std::size_t>(o)].t_begin <= t) old = o;
    const Segment<S>& s = shared->segments[static_cast<std::size_t>(old)];
    return shared->state(old, std::clamp(t, s.t_begin, s.t_end));
  };
  guess.input = [shared](double t) { return shared->input_at(shared->segment_at(t), t); };
  return guess;
}

}  // namespace saltus::timefreezing
