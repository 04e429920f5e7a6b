// Definitions of simulator.hpp (see there for the method).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <saltus/hybrid/simulation/simulator.hpp>

namespace saltus {

template <Scene S>
Simulator<S>::Simulator(const S& scene, SimulationOptions options)
    : scene_(scene), options_(std::move(options)), transitions_(scene, options_), dopri_(options_.integrator) {
  validate_scene(scene);
  SALTUS_REQUIRE(options_.integrator.relative_tolerance > 0 && options_.integrator.absolute_tolerance > 0, "integrator tolerances must be > 0");
  // The backend: Dormand-Prince (member, always there) or CVODE (BDF/Adams), created once here.
  // CVODE is the optional component saltus::cvode: its code is compiled into a scene's
  // instantiation only where SALTUS_WITH_CVODE is defined (the target saltus::cvode sets it).
#if defined(SALTUS_WITH_CVODE) && SALTUS_WITH_CVODE
  if (options_.integrator.kind != IntegratorKind::DormandPrince) {
    cvode_ = decltype(cvode_)(new CvodeIntegrator<S>(options_.integrator), [](CvodeIntegrator<S>* p) { delete p; });
    cvode_->set_gap_tolerance(options_.impact.gap_tolerance);
  }
#else
  SALTUS_REQUIRE(options_.integrator.kind == IntegratorKind::DormandPrince, "integrator '",
                 to_string(options_.integrator.kind),
                 "': this scene's machinery was compiled without CVODE; link the component saltus::cvode "
                 "(find_package(Saltus COMPONENTS cvode)) to the target that instantiates the scene, or use "
                 "Dormand-Prince");
#endif
  dopri_.set_gap_tolerance(options_.impact.gap_tolerance);
}

template <Scene S>
Simulator<S>::~Simulator() = default;

template <Scene S>
HybridTrajectory<S> Simulator<S>::run(const State& x0, double t0, double t_final, const InputLaw<S>& input) {
  return run_impl(x0, std::nullopt, t0, t_final, input);
}

template <Scene S>
HybridTrajectory<S> Simulator<S>::run(const State& x0, double t0, double t_final, const SegmentedInputLaw<S>& input) {
  SALTUS_REQUIRE(static_cast<bool>(input), "the input law is empty");
  int segment = 0;
  // The law the integration and the event physics call: the segmented law at the current index.
  const InputLaw<S> bound = [&input, &segment](double t, const State& x, const Mode<nc>& mode) {
    return input(segment, t, x, mode);
  };
  HybridTrajectory<S> traj = run_impl(x0, std::nullopt, t0, t_final, bound, &segment);
  // A self-contained law for the trajectory (simulator.hpp): the segment containing t.
  std::vector<double> event_times;
  event_times.reserve(traj.events.size());
  for (const auto& ev : traj.events) event_times.push_back(ev.t);
  traj.input = [input, event_times = std::move(event_times)](double t, const State& x, const Mode<nc>& mode) {
    const int i = static_cast<int>(std::upper_bound(event_times.begin(), event_times.end(), t) - event_times.begin());
    return input(i, t, x, mode);
  };
  apply_sliding_to_input(traj);
  return traj;
}

template <Scene S>
void Simulator<S>::apply_sliding_to_input(HybridTrajectory<S>& traj) const {
  struct Sliding {
    double t_begin, t_end;
    Mode<nc> mode, open_mode;
    int contact;
    double floor;
  };
  std::vector<Sliding> sliding;
  for (const auto& seg : traj.segments)
    if (seg.sliding_contact >= 0)
      sliding.push_back({seg.t_begin, seg.t_end, seg.mode, seg.sliding_open_mode, seg.sliding_contact,
                         seg.sliding_force_floor});
  if (sliding.empty()) return;
  traj.input = [law = traj.input, sliding = std::move(sliding), scene = &scene_](double t, const State& x,
                                                                                 const Mode<nc>& mode) {
    for (const Sliding& s : sliding)
      if (t >= s.t_begin && t <= s.t_end && mode == s.mode) {
        FlowWorkspace<S> ws;
        return sliding_input(*scene, law, t, x, mode, s.contact, s.open_mode, s.floor, ws);
      }
    return law(t, x, mode);
  };
}

template <Scene S>
HybridTrajectory<S> Simulator<S>::run(const State& x0, const Mode<nc>& mode0, double t0, double t_final,
                                      const InputLaw<S>& input) {
  return run_impl(x0, mode0, t0, t_final, input);
}

template <Scene S>
HybridTrajectory<S> Simulator<S>::run_impl(const State& x0, std::optional<Mode<nc>> mode0, double t0, double t_final,
                                           const InputLaw<S>& input, int* segment) {
  const auto wall_start = std::chrono::steady_clock::now();
  require_finite(x0, "initial state x0");
  SALTUS_REQUIRE(std::isfinite(t0) && std::isfinite(t_final) && t_final > t0, 
                "simulation interval must be finite with t_final > t0, got [", t0, ", ", t_final, "]");
  SALTUS_REQUIRE(static_cast<bool>(input), "the input law is empty");
  HybridTrajectory<S> traj;
  traj.input = input;
  for (double b : options_.breakpoints)
    if (b > t0 && b < t_final) traj.input_breakpoints.push_back(b);
  std::sort(traj.input_breakpoints.begin(), traj.input_breakpoints.end());
  traj.input_breakpoints.erase(std::unique(traj.input_breakpoints.begin(), traj.input_breakpoints.end()),
                               traj.input_breakpoints.end());
  ModeSystem<S> sys(scene_, input);
  touchdown_times_.clear();
  touchdown_contacts_.clear();
  touchdown_speeds_.clear();
  touchdown_state_scale_ = 0.0;
  accumulation_start_ = t0;
  carried_uncertainty_ = 0.0;
  rest_impact_seen_ = false;
  same_instant_events_ = 0;

  double t = t0;
  State x = x0;
  Mode<nc> mode;
  if (mode0) {
    sys.set_mode(*mode0);  // a law that switches with the contact mode is judged with the given mode's input
    // A given slip into Painleve's inconsistent configuration: refused by check_initial_mode, or
    // resolved by the impact without collision (SimulationOptions::painleve).
    const int inconsistent =
        options_.painleve.resolution == InconsistentContactResolution::ImpactWithoutCollision
            ? transitions_.inconsistent_slip(x0, sys.input(t0, x0), *mode0)
            : -1;
    if (inconsistent >= 0) {
      Event<S> ev = transitions_.resolve_inconsistent(sys, t, x, *mode0, inconsistent);
      for (const auto& tr : ev.transitions) {
        if (tr.selection_solutions > 1) ++traj.statistics.ambiguous_selections;
        if (tr.sliding_contact >= 0) ++traj.statistics.sliding_events;
      }
      x = ev.x_plus;
      mode = ev.mode_after;
      traj.events.push_back(std::move(ev));
      traj.segments.push_back(Segment<S>{traj.events.back().mode_before, t, t, {}});
    } else {
      check_initial_mode(x0, *mode0, sys.input(t0, x0));
      mode = *mode0;
    }
  } else {
    auto start = transitions_.start(sys, t, x);
    mode = start.mode;
    if (start.sliding_contact >= 0) ++traj.statistics.sliding_events;
    if (start.selection_solutions > 1) ++traj.statistics.ambiguous_selections;
    if (start.impact) {
      x = start.impact->x_plus;
      traj.events.push_back(std::move(*start.impact));
      traj.segments.push_back(Segment<S>{traj.events.back().mode_before, t, t, {}});
    }
  }
  if (segment) *segment = static_cast<int>(traj.segments.size());

  SimulationStatistics& stats = traj.statistics;
  while (true) {
    sys.set_mode(mode);
    Segment<S> seg;
    seg.mode = mode;
    seg.t_begin = t;
    seg.sliding_contact = sys.sliding_contact();
    if (seg.sliding_contact >= 0) {
      seg.sliding_open_mode = sys.sliding_open_mode();
      seg.sliding_force_floor = sys.sliding_force_floor();
    }
    const long rhs_before = sys.rhs_evaluations();
    const State x_begin = x;
    SegmentEndOf<S> end;
    std::vector<Guard> jumped;  // force guards made due by an input jump at a breakpoint
    while (true) {
      // Integrate up to the next breakpoint of the input, or t_final.
      double t_stop = t_final;
      for (double b : options_.breakpoints)
        if (b > t * (1 + 1e-15) + 1e-300 && b < t_stop) t_stop = b;
      DenseOutput<nx>* dense = options_.record_dense_output ? &seg.x : nullptr;
      sys.set_input_jump(t_stop);  // the step that ends at a breakpoint sees the input before it
#if defined(SALTUS_WITH_CVODE) && SALTUS_WITH_CVODE
      end = cvode_ ? cvode_->integrate(sys, t, x, t_stop, options_.simultaneity, dense)
                   : dopri_.integrate(sys, t, x, t_stop, options_.simultaneity, dense);
#else
      end = dopri_.integrate(sys, t, x, t_stop, options_.simultaneity, dense);
#endif
      sys.set_input_jump(std::numeric_limits<double>::infinity());
      stats.steps += end.steps;
      stats.rejected_steps += end.rejected_steps;
      t = end.t;
      if (end.at_guard || t_stop == t_final) break;
      // At a breakpoint the input may jump so that the mode is no longer consistent under the
      // input after it (a thrust that outgrows the weight: lambda_n < 0 at once, with no root
      // inside a step). A force guard (release, slip onset) due under that input is an event at
      // the breakpoint; the state's guards (gaps, slip velocities) do not jump and are left to
      // the integrator's location (two corners landing together just after a breakpoint stay one
      // simultaneous event).
      jumped = transitions_.guards_due(sys, t, x);
      std::erase_if(jumped, [](const Guard& g) { return g.kind == GuardKind::Touchdown || g.kind == GuardKind::Stop; });
      if (!jumped.empty()) {
        end.at_guard = true;
        break;
      }
    }
    stats.rhs_evaluations += sys.rhs_evaluations() - rhs_before;
    check_no_penetration(x_begin, x, mode, end.t);
    seg.t_end = end.t;
    traj.segments.push_back(std::move(seg));
    if (!end.at_guard) break;

    // A segmented law sees the post-event segment while the event is resolved (input_law.hpp).
    if (segment) *segment = static_cast<int>(traj.segments.size());
    const bool input_jump = !jumped.empty();
    std::vector<Guard> fired = std::move(jumped);
    for (int k = 0; k < sys.guards().count; ++k)
      if (end.fired[k]) fired.push_back(sys.guards()[k]);
    Event<S> ev = transitions_.resolve(sys, t, x, mode, fired);
    ev.input_jump = input_jump;
    for (const auto& tr : ev.transitions) {
      if (tr.selection_solutions > 1) ++traj.statistics.ambiguous_selections;
      if (tr.sliding_contact >= 0) ++traj.statistics.sliding_events;
    }
    // Zeno bookkeeping on every touchdown event (file comment).
    bool zeno = false;
    bool touchdown = false, slower_than_rest = false;
    std::array<bool, nc> touched{};
    double speed = 0.0;
    Kinematics<S> kin_minus;
    for (const Guard& g : ev.guards()) {
      if (g.kind != GuardKind::Touchdown) continue;
      if (!touchdown)
        evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()),
                            kin_minus);
      touchdown = true;
      touched[g.contact] = true;
      speed = std::max(speed, -kin_minus.contacts[g.contact].zeta_n);
      if (options_.rest_velocity > 0 && -kin_minus.contacts[g.contact].zeta_n < options_.rest_velocity)
        slower_than_rest = true;
    }
    if (touchdown) {
      touchdown_state_scale_ = std::max(touchdown_state_scale_, x.cwiseAbs().maxCoeff());
      zeno = record_touchdown(t, touched, speed, slower_than_rest, traj);
    }
    // Events that follow each other at one instant without the motion advancing: a cycle of
    // transitions the chain check did not catch (e.g. a contact that the mode selection opens but
    // the flow drives into the surface). Stop with the cause rather than spin to max_events.
    same_instant_events_ = (!traj.events.empty() && traj.events.back().t == t) ? same_instant_events_ + 1 : 0;
    SALTUS_CHECK_NUMERICS(same_instant_events_ < options_.max_chain, "events stall at t = ", t, ": ",
                          same_instant_events_ + 1, " consecutive events at this instant, the last fired by ",
                          ev.guards().empty() ? std::string("no guard")
                                              : std::string(to_string(ev.guards().front().kind)) + " of contact '" +
                                                    scene_.contact(ev.guards().front().contact).name + "'",
                          " (mode after: ", describe(scene_, ev.mode_after), ")");
    x = ev.x_plus;
    mode = ev.mode_after;
    traj.events.push_back(std::move(ev));
    if (zeno && !(options_.zeno_completion && traj.zeno_time < t_final)) {
      traj.status = SimulationStatus::Zeno;
      break;
    }
    if (zeno) complete_accumulation(sys, t, x, mode, traj, segment);
    if (static_cast<int>(traj.events.size()) >= options_.max_events) {
      traj.status = SimulationStatus::MaxEvents;
      break;
    }
  }
  traj.set_final_state(x);
  for (const auto& ev : traj.events)
    for (const auto& tr : ev.transitions) stats.impacts_without_collision += tr.impact_without_collision ? 1 : 0;
  apply_sliding_to_input(traj);
  stats.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return traj;
}

template <Scene S>
bool Simulator<S>::record_touchdown(double t, const std::array<bool, nc>& touched, double speed,
                                    bool slower_than_rest, HybridTrajectory<S>& traj) {
  auto& times = touchdown_times_;
  times.push_back(t);
  touchdown_contacts_.push_back(touched);
  touchdown_speeds_.push_back(speed);
  // The rest criterion ends a bouncing accumulation by itself: Zeno only if touchdowns go on
  // after an impact it made inelastic (the impact that brings a ball to rest is not one).
  const bool rest_acted_before = rest_impact_seen_;
  rest_impact_seen_ = rest_impact_seen_ || slower_than_rest;
  if (options_.rest_velocity > 0 && !rest_acted_before) return false;
  const std::size_t m = times.size();
  // Near the time resolution (the last interval below 1e3 simultaneity windows) the touchdowns
  // are about to merge into events at one instant, near the gap tolerance (the approach speed
  // times the last interval below 1e3 gap tolerances) they are located on motions of its size: 4
  // ratios suffice there (file comment).
  int n = options_.zeno_bounces;
  if (m >= 2) {
    const double last = times[m - 1] - times[m - 2];
    if (last < 1e3 * options_.simultaneity || touchdown_speeds_[m - 1] * last < 1e3 * options_.impact.gap_tolerance)
      n = std::min(n, 4);
  }
  for (int period = 1; period <= 2; ++period) {
    // n ratios of intervals `period` apart need n + period intervals, n + period + 1 times.
    if (static_cast<int>(m) < n + period + 1) continue;
    auto interval = [&](int back) { return times[m - 1 - back] - times[m - 2 - back]; };  // back = 0: last
    double r_min = 1.0, r_max = 0.0;
    bool positive = true;
    for (int k = 0; k < n && positive; ++k) {
      const double f1 = interval(k), f0 = interval(k + period);
      positive = f0 > 0 && f1 > 0;
      if (!positive) break;
      const double r = f1 / f0;
      r_min = std::min(r_min, r);
      r_max = std::max(r_max, r);
    }
    if (!positive || !(r_max < 1.0 && r_max - r_min < 0.05)) continue;
    extrapolate_accumulation(period, 0.5 * (r_min + r_max), traj);
    zeno_window_ = n + period + 1;
    return true;
  }
  return false;
}

template <Scene S>
void Simulator<S>::complete_accumulation(ModeSystem<S>& sys, double& t, State& x, Mode<nc>& mode,
                                         HybridTrajectory<S>& traj, int* segment) {
  ZenoCompletion record;
  record.t = std::max(t, traj.zeno_time);
  record.uncertainty = traj.zeno_time_uncertainty;
  record.last_touchdown = t;
  // The accumulating contacts: those of the touchdowns in the detection window.
  std::array<bool, nc> accumulating{};
  const std::size_t m = touchdown_times_.size(), window = std::min(m, static_cast<std::size_t>(zeno_window_));
  for (std::size_t k = m - window; k < m; ++k)
    for (int i = 0; i < nc; ++i) accumulating[i] = accumulating[i] || touchdown_contacts_[k][i];
  for (int i = 0; i < nc; ++i)
    if (accumulating[i]) record.contacts.push_back(i);
  // The unresolved tail [t, record.t]: the state after the last touchdown, held.
  Segment<S> tail;
  tail.mode = mode;
  tail.t_begin = t;
  tail.t_end = record.t;
  if (options_.record_dense_output && record.t > t) {
    PolynomialPiece<nx> held;
    held.t0 = held.t_ref = t;
    held.t1 = record.t;
    held.h = record.t - t;
    held.c.col(0) = x;  // degree 0
    tail.x.append(held);
  }
  traj.segments.push_back(std::move(tail));
  if (segment) *segment = static_cast<int>(traj.segments.size());
  // The limit state, and the mode a start from it selects (zeno_completion.hpp).
  const State limit = zeno_limit_state(scene_, x, mode, accumulating, options_.impact.gap_tolerance, projection_);
  auto start = transitions_.start(sys, record.t, limit);
  if (start.sliding_contact >= 0) ++traj.statistics.sliding_events;
  if (start.selection_solutions > 1) ++traj.statistics.ambiguous_selections;
  Transition<S> completion;
  completion.mode_before = mode;
  completion.mode_after = start.impact ? start.impact->mode_before : start.mode;
  completion.x_before = x;
  completion.x_after = limit;
  completion.impact = true;
  completion.zeno_completion = true;
  completion.selection_solutions = start.selection_solutions;
  completion.sliding_contact = start.sliding_contact;
  Event<S> ev;
  ev.t = record.t;
  ev.x_minus = x;
  ev.mode_before = mode;
  ev.transitions.push_back(std::move(completion));
  if (start.impact) ev.transitions.insert(ev.transitions.end(), start.impact->transitions.begin(),
                                          start.impact->transitions.end());
  ev.x_plus = start.impact ? start.impact->x_plus : limit;
  ev.mode_after = start.mode;
  record.event = static_cast<int>(traj.events.size());
  traj.zeno_completions.push_back(std::move(record));
  t = ev.t;
  x = ev.x_plus;
  mode = ev.mode_after;
  traj.events.push_back(std::move(ev));
  // A new accumulation is detected on the touchdowns after this one only.
  touchdown_times_.clear();
  touchdown_contacts_.clear();
  touchdown_speeds_.clear();
  // The touchdowns after it carry this accumulation time's error one to one (accumulation_time.hpp).
  accumulation_start_ = t;
  carried_uncertainty_ = traj.zeno_completions.back().uncertainty;
  rest_impact_seen_ = false;
  same_instant_events_ = 0;
}

template <Scene S>
void Simulator<S>::extrapolate_accumulation(int period, double ratio, HybridTrajectory<S>& traj) const {
  const AccumulationTime a = extrapolate_accumulation_time(touchdown_times_, period, ratio);
  traj.zeno_time = a.t;
  traj.zeno_time_extrapolation_uncertainty = a.extrapolation_uncertainty;
  const IntegratorOptions& io = options_.integrator;
  // The CVODE backends' touchdown times were measured up to 3200 rho T off, not in proportion to
  // their tolerances (accumulation_time.hpp): no bound from the tolerances is stated for them.
  traj.zeno_time_integration_uncertainty =
      io.kind == IntegratorKind::DormandPrince
          ? touchdown_integration_uncertainty(a, touchdown_times_, io.relative_tolerance, io.absolute_tolerance,
                                              touchdown_state_scale_, io.root_tolerance, accumulation_start_,
                                              carried_uncertainty_)
          : std::numeric_limits<double>::infinity();
  traj.zeno_time_uncertainty = traj.zeno_time_extrapolation_uncertainty + traj.zeno_time_integration_uncertainty;
}

template <Scene S>
void Simulator<S>::check_no_penetration(const State& x_begin, const State& x_end, const Mode<nc>& mode,
                                        double t) const {
  Kinematics<S> k0, k1;
  evaluate_kinematics(scene_, VecT<double, nq>(x_begin.template head<nq>()),
                      VecT<double, nq>(x_begin.template tail<nq>()), k0);
  evaluate_kinematics(scene_, VecT<double, nq>(x_end.template head<nq>()), VecT<double, nq>(x_end.template tail<nq>()),
                      k1);
  const double tol = options_.impact.gap_tolerance;
  for (int i = 0; i < nc; ++i) {
    if (mode[i].closed()) continue;
    const double gap = k1.contacts[i].gap;
    SALTUS_CHECK_NUMERICS(gap >= -tol || gap >= k0.contacts[i].gap, "missed touchdown: open contact '",
                          scene_.contact(i).name, "' is at gap ", gap, " < -", tol, " at t = ", t,
                          " (it started the segment at gap ", k0.contacts[i].gap,
                          "); reduce the integrator's max_step or raise guard_samples");
  }
}

template <Scene S>
void Simulator<S>::check_initial_mode(const State& x, const Mode<nc>& mode, const Input& u) const {
  require_finite(x, "initial state x0");
  FlowWorkspace<S> ws;
  evaluate_flow(scene_, mode, x, u, ws);
  const auto& kin = ws.kin;
  const double gap_tol = options_.impact.gap_tolerance;
  const double v_tol = options_.selection.velocity_tolerance * std::max(1.0, x.template tail<nq>().cwiseAbs().maxCoeff());
  double force_scale = (kin.M * ws.a_free).cwiseAbs().maxCoeff();
  for (int i = 0; i < nc; ++i)
    force_scale = std::max({force_scale, std::abs(ws.force[i].normal), ws.force[i].tangent.cwiseAbs().maxCoeff()});
  const double f_tol = options_.guard_tolerance * std::max(1.0, force_scale);
  for (int i = 0; i < nc; ++i) {
    const auto& c = kin.contacts[i];
    const std::string& name = scene_.contact(i).name;
    const ContactState& st = mode[i];
    if (!st.closed()) {
      SALTUS_REQUIRE(c.gap >= -gap_tol, "initial mode: contact '", name, "' is given open but penetrates (gap ",
                     c.gap, ")");
      continue;
    }
    // Below the surface by a little is the drift of a stance phase (a state taken from an earlier
    // run); above it, the contact does not touch.
    SALTUS_REQUIRE(c.gap <= gap_tol && c.gap >= -100 * gap_tol, "initial mode: contact '", name,
                   "' is given closed but its gap is ", c.gap, " (accepted: [", -100 * gap_tol, ", ", gap_tol, "])");
    SALTUS_REQUIRE(std::abs(c.zeta_n) <= v_tol, "initial mode: contact '", name,
                   "' is given closed but its normal velocity is ", c.zeta_n, " (an impact or a lift-off, not a mode)");
    const auto& f = ws.force[i];
    SALTUS_REQUIRE(f.normal >= -f_tol, "initial mode: contact '", name, "' is given ", to_string(st.mode),
                   " but the normal force it implies is ", f.normal,
                   " < 0: the mode is inconsistent (if it slides, the acceleration-level contact problem may have "
                   "no solution with it: a Painleve configuration)");
    const int nt = c.tangents;
    if (nt == 0) continue;
    const double mu = scene_.contact(i).mu;
    double speed2 = 0.0, along = 0.0;
    for (int k = 0; k < nt && k < 2; ++k) {
      speed2 += c.zeta_t[k] * c.zeta_t[k];
      along += c.zeta_t[k] * st.slip_direction[k];
    }
    const double speed = std::sqrt(speed2);
    if (st.mode == ContactMode::Stick) {
      SALTUS_REQUIRE(speed <= v_tol, "initial mode: contact '", name, "' is given sticking but slides at ", speed,
                     " m/s");
      double tangential2 = 0.0;  // over the contact's nt <= 2 tangents
      for (int k = 0; k < nt && k < 2; ++k) tangential2 += f.tangent[k] * f.tangent[k];
      const double tangential = std::sqrt(tangential2);
      SALTUS_REQUIRE(tangential <= mu * f.normal + f_tol, "initial mode: contact '", name,
                     "' is given sticking but its force leaves the friction cone (|lambda_t| = ", tangential,
                     " > mu lambda_n = ", mu * f.normal, ")");
    } else if (speed > v_tol) {
      SALTUS_REQUIRE(along >= (1 - 1e-6) * speed, "initial mode: contact '", name,
                     "' is given slipping along a direction that is not its sliding velocity (zeta_t . d = ", along,
                     ", |zeta_t| = ", speed, ")");
    }
  }
}

}  // namespace saltus
