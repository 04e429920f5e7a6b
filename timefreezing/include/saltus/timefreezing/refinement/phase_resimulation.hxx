// The event-driven re-simulation of a refined reference (refinement.hpp, PhaseResimulation): (a)
// phase by phase from each phase's start state (or window by window inside each phase, from the
// reference's state at each window's start), (b) over the whole horizon open loop.
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/vocabulary/guard.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <utility>

namespace saltus::timefreezing {

namespace detail {

inline std::set<std::pair<int, int>> guard_set(const std::vector<Guard>& guards) {
  std::set<std::pair<int, int>> s;
  for (const Guard& g : guards) s.insert({g.contact, static_cast<int>(g.kind)});
  return s;
}

/// Runs the simulator from (x_start, mode) at t0 to t1; when the simulator refuses the mode as an
/// initial mode (check_initial_mode), runs from the state alone and says so in `note`.
template <Scene S>
HybridTrajectory<S> run_from(Simulator<S>& sim, const VecT<double, 2 * S::nq>& x_start, const Mode<S::nc>& mode,
                             double t0, double t1, const InputLaw<S>& law, std::string& note) {
  try {
    return sim.run(x_start, mode, t0, t1, law);
  } catch (const InvalidArgument& e) {
    note = std::string("the simulator chose its own initial mode: ") + e.what();
    return sim.run(x_start, t0, t1, law);
  }
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

/// The state of `run` at t before any event at t: x- of the first event within `tolerance` of t
/// (the simulator locates an event to its own tolerance, a hair before or after the node), else
/// the state on the segment that contains t.
template <Scene S>
VecT<double, 2 * S::nq> state_before_events(const HybridTrajectory<S>& run, double t, double tolerance) {
  for (const auto& ev : run.events)
    if (std::abs(ev.t - t) <= tolerance) return ev.x_minus;
  const int k = run.segment_at(t);
  const Segment<S>& s = run.segments[static_cast<std::size_t>(k)];
  return run.state(k, std::clamp(t, s.t_begin, s.t_end));
}

/// (a) of the checks on one stretch of a phase ending at `until`: the distance at every node of
/// it, through events the simulator finds inside the phase (a contact whose force and gap are both
/// zero on the reference can be labelled open or closed: the motion is the same, and the distance
/// says whether it is), which are counted and their descriptions collected in `unplanned`.
template <Scene S>
void compare_phase(const S& scene, const HybridTrajectory<S>& traj, int p, const HybridTrajectory<S>& run,
                   const std::vector<double>& nodes, double until, double t1, double tolerance, PhaseResimulation& r,
                   std::vector<std::string>& unplanned) {
  for (double t : nodes) {
    const double e = (state_before_events(run, t, tolerance) - traj.state(p, t)).cwiseAbs().maxCoeff();
    r.max_error = std::max(r.max_error, e);
    if (t == t1) r.end_error = e;
    r.compared_until = t;
  }
  const double stop = until < t1 ? until : t1 - tolerance;  // the phase's end event is not unplanned
  for (const auto& ev : run.events) {
    if (ev.t >= stop) break;
    ++r.unplanned_events;
    std::ostringstream named;
    named << describe_event(scene, ScheduleEvent{ev.guards()}) << " at t = " << ev.t;
    unplanned.push_back(named.str());
  }
}

/// The note on the unplanned events of a phase (the first three named).
inline std::string unplanned_note(const std::vector<std::string>& unplanned) {
  std::ostringstream note;
  note << unplanned.size() << " unplanned event(s) inside the phase (";
  for (std::size_t k = 0; k < unplanned.size() && k < 3; ++k) note << (k > 0 ? ", " : "") << unplanned[k];
  note << (unplanned.size() > 3 ? ", ...)" : ")");
  return note.str();
}

/// The starts of the re-simulation windows of a phase: its first node, then the first node at
/// least `window` after the previous start (window <= 0: the phase's start alone).
inline std::vector<double> window_starts(const std::vector<double>& nodes, double window) {
  std::vector<double> starts{nodes.front()};
  if (window <= 0.0) return starts;
  for (std::size_t k = 1; k + 1 < nodes.size(); ++k)
    if (nodes[k] - starts.back() >= window * (1.0 - 1e-9)) starts.push_back(nodes[k]);  // rounding of the nodes
  return starts;
}

/// The guards of `found` less the friction guards (stop, slip onset) of a contact that the same
/// boundary releases: where lambda_n reaches 0 the friction cone is a point, so the simulator may
/// fire a released contact's slip onset at the instant of its release, and which of the two its
/// event location finds first is decided by round-off. The contact is open after either, so its
/// friction guard says nothing about the motion (the mode after the boundary is compared as well).
inline std::set<std::pair<int, int>> without_friction_guards_of_released(std::set<std::pair<int, int>> found) {
  for (auto it = found.begin(); it != found.end();) {
    const auto kind = static_cast<GuardKind>(it->second);
    const bool friction = kind == GuardKind::SlipOnset || kind == GuardKind::Stop;
    if (friction && found.count({it->first, static_cast<int>(GuardKind::Release)})) it = found.erase(it);
    else ++it;
  }
  return found;
}

/// The boundary at the end of phase p: the events the simulator finds within `tolerance` of t1,
/// their guards against the schedule's (a released contact's friction guards aside on both sides:
/// without_friction_guards_of_released), the mode after them against phase p + 1's, and the state
/// after them (x+ of the last one, else the state at t1) against the reference's x+.
template <Scene S>
void judge_boundary(const S& scene, const HybridTrajectory<S>& run, const ModeSchedule<S::nc>& schedule, const Mode<S::nc>& next,
                    const VecT<double, 2 * S::nq>& x_plus, int p, double t1, double tolerance, PhaseResimulation& r) {
  std::set<std::pair<int, int>> found;
  int last_at_boundary = -1;
  r.event_time_error = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < static_cast<int>(run.events.size()); ++k) {
    const auto& ev = run.events[static_cast<std::size_t>(k)];
    if (std::abs(ev.t - t1) > tolerance) continue;
    if (last_at_boundary < 0) r.event_time_error = ev.t - t1;
    last_at_boundary = k;
    for (const auto& g : guard_set(ev.guards())) found.insert(g);
  }
  const VecT<double, 2 * S::nq> x_after =
      last_at_boundary >= 0 ? run.events[static_cast<std::size_t>(last_at_boundary)].x_plus : state_before_events(run, t1, tolerance);
  r.x_plus_error = (x_after - x_plus).cwiseAbs().maxCoeff();
  r.event_guards_match = without_friction_guards_of_released(found) ==
                         without_friction_guards_of_released(guard_set(schedule.events[static_cast<std::size_t>(p)].guards));
  // the mode after the boundary's events: the event's own (a run that ends at the event has no
  // segment after it), else the mode of the segment at t1
  const Mode<S::nc>& simulated_next = last_at_boundary >= 0 ? run.events[static_cast<std::size_t>(last_at_boundary)].mode_after
                                                             : run.segments[static_cast<std::size_t>(run.segment_at(t1))].mode;
  r.next_mode_matches = same_branches(simulated_next, next);
  std::ostringstream why;
  if (last_at_boundary < 0) {
    why << "no event within " << tolerance << " s of the phase's end";
    for (const auto& ev : run.events)
      if (ev.t > t1) {
        why << " (the next one at t = " << ev.t << ")";
        break;
      }
  } else if (!r.event_guards_match) {
    const auto list = [](const std::set<std::pair<int, int>>& guards) {
      std::string out;
      for (const auto& [contact, kind] : guards)
        out += (out.empty() ? "" : ", ") + std::string(to_string(static_cast<GuardKind>(kind))) + " " + std::to_string(contact);
      return out;
    };
    why << "the simulator's event at the phase's end has other guards (" << list(found) << "; the schedule's: "
        << list(guard_set(schedule.events[static_cast<std::size_t>(p)].guards)) << ")";
  }
  if (!r.next_mode_matches)
    why << (why.tellp() > 0 ? ", " : "") << "after it the simulator is in another mode (" << describe(scene, simulated_next)
        << "; the schedule's: " << describe(scene, next) << ")";
  if (why.tellp() > 0) r.note += std::string(r.note.empty() ? "" : "; ") + why.str();
}

/// The state x brought onto the contacts closed in `mode` (and in `released`, the contacts closed
/// before a release at this start); returns ||change||_inf.
template <Scene S>
double project_on_contacts(const S& scene, Mode<S::nc> manifold, const Mode<S::nc>* released, VecT<double, 2 * S::nq>& x) {
  if (released)
    for (int i = 0; i < S::nc; ++i)
      if (!manifold[i].closed() && (*released)[i].closed()) manifold[i] = ContactState::slip(Eigen::Vector2d::Zero());
  const VecT<double, 2 * S::nq> unprojected = x;
  ConstraintProjection<S> projection;
  projection.project(scene, manifold, x);
  return (x - unprojected).cwiseAbs().maxCoeff();
}

/// The optimal input as phase p's re-simulation applies it: the law of time (phase p's input, held
/// before its start) on both sides of the phase's end, where a release (lambda_n = 0 at x-) or a
/// slip onset happens because the next phase's input drives the force out of its cone; except
/// before a touchdown: once the plant is in phase p + 1's mode before the phase's end, it gets
/// phase p + 1's first input (the ex-post extension of reference spreading). The simulator
/// locates an event to its own tolerance, and the re-simulation's drift (within the check's
/// 1e-6) may bring a touchdown a hair before the reference's; under the law of time the
/// transition would then select the post-impact mode with the flight's last input, under which
/// a stance that starts loaded under its own first input may be inconsistent (the hopper's
/// touchdowns: lambda_n = 68 N under the stance's first input, -21 N under the flight's last),
/// and the simulator would bounce where the reference lands. Before a release the law of time
/// stays: a stance whose force is zero over its last element (an optimum may put it there) may be
/// released by the simulator at any node of that element with the same motion, and the flight's
/// input from then on would lift it early; a late event keeps the law of time as well, an input
/// jump at the phase's end may be what fires it (RefinementOptions::releases_at_input_jumps).
template <Scene S>
InputLaw<S> boundary_input_law(const HybridTrajectory<S>& traj, int p) {
  const Segment<S>& seg = traj.segments[static_cast<std::size_t>(p)];
  const double t0 = seg.t_begin, t1 = seg.t_end;
  if (p + 1 >= static_cast<int>(traj.segments.size()) || !traj.events[static_cast<std::size_t>(p)].impact())
    return [&traj, t0](double t, const VecT<double, 2 * S::nq>& x, const Mode<S::nc>& m) {
      return traj.input(std::max(t, t0), x, m);
    };
  const Mode<S::nc> here = seg.mode, next = traj.segments[static_cast<std::size_t>(p + 1)].mode;
  return [&traj, t0, t1, here, next](double t, const VecT<double, 2 * S::nq>& x, const Mode<S::nc>& m) {
    if (t < t1 && same_branches(m, next) && !same_branches(m, here)) return traj.input(t1, x, m);
    return traj.input(std::max(t, t0), x, m);
  };
}

/// Phase p re-simulated window by window (resimulate_phases): each window from the reference's
/// state at its start (the first from x+ of the event before it), projected onto the phase's
/// closed contacts; the last window runs past the phase's end and judges the boundary.
template <Scene S>
PhaseResimulation resimulate_phase(const S& scene, const HybridTrajectory<S>& traj, const ModeSchedule<S::nc>& schedule,
                                   const std::vector<double>& element_times, const SimulationOptions& simulation,
                                   double window, int p) {
  PhaseResimulation r;
  r.phase = p;
  const int P = static_cast<int>(traj.segments.size());
  const Segment<S>& seg = traj.segments[static_cast<std::size_t>(p)];
  const double t0 = seg.t_begin, t1 = seg.t_end;
  std::vector<double> nodes;
  for (double t : element_times)
    if (t >= t0 && t <= t1) nodes.push_back(t);
  if (t1 <= t0 || nodes.empty()) {
    r.note = "the phase has zero duration";
    return r;
  }
  const InputLaw<S> law = boundary_input_law(traj, p);
  SimulationOptions options = simulation;
  options.breakpoints = nodes;
  Simulator<S> sim(scene, options);
  const bool last = p + 1 == P;
  const double tolerance = 1e-6 * std::max(1.0, std::abs(t1));
  const std::vector<double> starts = window_starts(nodes, window);
  r.windows = static_cast<int>(starts.size());
  std::vector<std::string> unplanned;
  for (std::size_t w = 0; w < starts.size(); ++w) {
    const bool final_window = w + 1 == starts.size();
    const double from = starts[w], until = final_window ? t1 : starts[w + 1];
    VecT<double, 2 * S::nq> x_start = w == 0 && p > 0 ? traj.events[static_cast<std::size_t>(p - 1)].x_plus : traj.state(p, from);
    if (p > 0 || w > 0)  // onto the contacts closed in this phase or released at its start (their drift)
      r.start_projection = std::max(r.start_projection,
                                    project_on_contacts(scene, seg.mode, w == 0 ? &traj.segments[static_cast<std::size_t>(p - 1)].mode : nullptr, x_start));
    const double margin = !final_window || last ? 0.0 : std::max(0.05 * (t1 - t0), 1e-3);
    HybridTrajectory<S> run;
    try {
      run = run_from(sim, x_start, seg.mode, from, until + margin, law, r.note);
    } catch (const Error& e) {
      r.max_error = r.end_error = r.event_time_error = r.x_plus_error = std::numeric_limits<double>::quiet_NaN();
      r.event_guards_match = r.next_mode_matches = false;
      r.note += std::string(r.note.empty() ? "" : "; ") + "the simulation failed: " + e.what();
      return r;
    }
    std::vector<double> compared;
    for (double t : nodes)
      if (t >= from && t <= until) compared.push_back(t);  // the start too: the projection's distance
    compare_phase(scene, traj, p, run, compared, until, t1, tolerance, r, unplanned);
    if (!final_window) continue;
    if (last) r.event_time_error = std::numeric_limits<double>::quiet_NaN();
    else
      judge_boundary(scene, run, schedule, traj.segments[static_cast<std::size_t>(p + 1)].mode,
                     traj.events[static_cast<std::size_t>(p)].x_plus, p, t1, tolerance, r);
  }
  if (!unplanned.empty()) r.note = unplanned_note(unplanned) + (r.note.empty() ? "" : "; " + r.note);
  return r;
}

}  // namespace detail

template <Scene S>
std::vector<PhaseResimulation> resimulate_phases(const S& scene, const HybridTrajectory<S>& traj,
                                                 const ModeSchedule<S::nc>& schedule,
                                                 const std::vector<double>& element_times,
                                                 const SimulationOptions& simulation, double window) {
  SALTUS_REQUIRE(std::isfinite(window) && window >= 0.0, "resimulate_phases: window must be >= 0 [s], got ", window);
  std::vector<PhaseResimulation> out;
  const int P = static_cast<int>(traj.segments.size());
  for (int p = 0; p < P; ++p) out.push_back(detail::resimulate_phase(scene, traj, schedule, element_times, simulation, window, p));
  return out;
}

template <Scene S>
OpenLoopResimulation resimulate_open_loop(const S& scene, const HybridTrajectory<S>& traj,
                                          const std::vector<double>& element_times,
                                          const SimulationOptions& simulation) {
  SimulationOptions options = simulation;
  options.breakpoints = element_times;
  Simulator<S> sim(scene, options);
  OpenLoopResimulation out;
  HybridTrajectory<S> run;
  try {
    run = sim.run(traj.state(0, traj.t_begin()), traj.t_begin(), traj.t_end(), traj.input);
  } catch (const Error& e) {
    out.max_error = std::numeric_limits<double>::quiet_NaN();
    out.note = std::string("the simulation failed: ") + e.what();
    return out;
  }
  const double tolerance = 1e-6 * std::max(1.0, std::abs(traj.t_end()));
  for (double t : element_times) {
    const VecT<double, 2 * S::nq> x_sim = detail::state_before_events(run, t, tolerance);
    const VecT<double, 2 * S::nq> x_ref = detail::state_before_events(traj, t, tolerance);
    out.max_error = std::max(out.max_error, (x_sim - x_ref).cwiseAbs().maxCoeff());
    out.compared_until = t;
  }
  out.events = static_cast<int>(run.events.size());
  return out;
}

}  // namespace saltus::timefreezing
