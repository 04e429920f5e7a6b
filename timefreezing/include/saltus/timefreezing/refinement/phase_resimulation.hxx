// The event-driven re-simulation of a refined reference (refinement.hpp, PhaseResimulation): (a)
// phase by phase from each phase's start state, (b) over the whole horizon open loop.
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
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

}  // namespace detail

template <Scene S>
std::vector<PhaseResimulation> resimulate_phases(const S& scene, const HybridTrajectory<S>& traj,
                                                 const ModeSchedule<S::nc>& schedule,
                                                 const std::vector<double>& element_times,
                                                 const SimulationOptions& simulation) {
  std::vector<PhaseResimulation> out;
  const int P = static_cast<int>(traj.segments.size());
  for (int p = 0; p < P; ++p) {
    PhaseResimulation r;
    r.phase = p;
    const Segment<S>& seg = traj.segments[static_cast<std::size_t>(p)];
    const double t0 = seg.t_begin, t1 = seg.t_end;
    std::vector<double> nodes;
    for (double t : element_times)
      if (t >= t0 && t <= t1) nodes.push_back(t);
    const double last_input_time = nodes.size() >= 2 ? nodes[nodes.size() - 2] : t0;
    const InputLaw<S> law = [&traj, t0, last_input_time](double t, const VecT<double, 2 * S::nq>& x, const Mode<S::nc>& m) {
      return traj.input(std::clamp(t, t0, last_input_time), x, m);
    };
    SimulationOptions options = simulation;
    options.breakpoints = nodes;
    Simulator<S> sim(scene, options);
    const bool last = p + 1 == P;
    const double margin = last ? 0.0 : std::max(0.05 * (t1 - t0), 1e-3);
    VecT<double, 2 * S::nq> x_start = p == 0 ? traj.state(0, t0) : traj.events[static_cast<std::size_t>(p - 1)].x_plus;
    if (p > 0) {  // onto the contacts closed in this phase or released at its start (their drift)
      Mode<S::nc> manifold = seg.mode;
      const Mode<S::nc>& before = traj.segments[static_cast<std::size_t>(p - 1)].mode;
      for (int i = 0; i < S::nc; ++i)
        if (!manifold[i].closed() && before[i].closed()) manifold[i] = ContactState::slip(Eigen::Vector2d::Zero());
      const VecT<double, 2 * S::nq> unprojected = x_start;
      ConstraintProjection<S> projection;
      projection.project(scene, manifold, x_start);
      r.start_projection = (x_start - unprojected).cwiseAbs().maxCoeff();
    }
    if (t1 <= t0) {
      r.note = "the phase has zero duration";
      out.push_back(r);
      continue;
    }
    HybridTrajectory<S> run;
    try {
      run = detail::run_from(sim, x_start, seg.mode, t0, t1 + margin, law, r.note);
    } catch (const Error& e) {
      r.max_error = r.end_error = r.event_time_error = std::numeric_limits<double>::quiet_NaN();
      r.event_guards_match = false;
      r.note += std::string(r.note.empty() ? "" : "; ") + "the simulation failed: " + e.what();
      out.push_back(r);
      continue;
    }
    const double t_event = run.events.empty() ? std::numeric_limits<double>::infinity() : run.events.front().t;
    const double tolerance = 1e-6 * std::max(1.0, std::abs(t1));
    if (t_event < t1 - tolerance)
      r.note += std::string(r.note.empty() ? "" : "; ") + "an unplanned event inside the phase at t = " + std::to_string(t_event) +
                " (" + describe_event(scene, ScheduleEvent{run.events.front().guards()}) + ")";
    for (double t : nodes) {
      // Before the simulator's first event its first segment; at a node within the tolerance of that
      // event (the phase's end, found a hair earlier or later) the event's x-.
      const bool at_event = std::abs(t - t_event) <= tolerance;
      if (t > t_event && !at_event) break;
      const VecT<double, 2 * S::nq> x_sim = at_event ? run.events.front().x_minus : run.state(0, std::min(t, run.segments.front().t_end));
      const double e = (x_sim - traj.state(p, t)).cwiseAbs().maxCoeff();
      r.max_error = std::max(r.max_error, e);
      if (t == t1) r.end_error = e;
    }
    if (last) {  // an event at the horizon's end (e.g. a stop exactly at T) is the motion's next one, not an error
      r.event_time_error = run.events.empty() ? std::numeric_limits<double>::quiet_NaN() : t_event - t1;
      r.event_guards_match = run.events.empty() || std::abs(t_event - t1) <= tolerance;
    } else if (run.events.empty()) {
      r.event_time_error = std::numeric_limits<double>::quiet_NaN();
      r.event_guards_match = false;
      r.note += std::string(r.note.empty() ? "" : "; ") + "no event found within the margin after the phase's end";
    } else {
      r.event_time_error = t_event - t1;
      r.event_guards_match = detail::guard_set(run.events.front().guards()) ==
                             detail::guard_set(schedule.events[static_cast<std::size_t>(p)].guards);
    }
    out.push_back(r);
  }
  return out;
}

template <Scene S>
OpenLoopResimulation resimulate_open_loop(const S& scene, const HybridTrajectory<S>& traj,
                                          const std::vector<double>& element_times,
                                          const SimulationOptions& simulation) {
  SimulationOptions options = simulation;
  options.breakpoints = element_times;
  Simulator<S> sim(scene, options);
  const HybridTrajectory<S> run = sim.run(traj.state(0, traj.t_begin()), traj.t_begin(), traj.t_end(), traj.input);
  OpenLoopResimulation out;
  out.compared_until = traj.t_begin();
  double& worst = out.max_error;
  double& compared_until = out.compared_until;
  for (double t : element_times) {
    const int p = traj.segment_at(t), q = run.segment_at(t);
    if (p != q) break;
    const Segment<S>& s = run.segments[static_cast<std::size_t>(q)];
    const Segment<S>& r = traj.segments[static_cast<std::size_t>(p)];
    worst = std::max(worst, (run.state(q, std::clamp(t, s.t_begin, s.t_end)) - traj.state(p, std::clamp(t, r.t_begin, r.t_end)))
                                .cwiseAbs()
                                .maxCoeff());
    compared_until = t;
  }
  return out;
}

}  // namespace saltus::timefreezing
