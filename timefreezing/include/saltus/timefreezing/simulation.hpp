// Simulation of the time-freezing system with FESD under a given input law: the FESD MPCC with
// its decisions fixed (no controls, no clock constraint, s = 1), solved by the MPCC homotopy, and
// the reading of its result: the frozen phases (impacts: the clock stands still while the
// auxiliary dynamics act, time-freezing Theorem 5) and the element boundaries where a switching
// function changes its active set (touchdowns into sliding, lift-offs, slip-stick).
#pragma once

#include <saltus/timefreezing/fesd.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <saltus/timefreezing/mpcc_solver.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

/// A frozen phase of the discrete solution: the clock stands still from tau_begin to tau_end,
/// the physical time is `time`, the state jumps from x_minus to x_plus (an impact).
template <int nx>
struct FrozenPhase {
  double tau_begin = 0.0, tau_end = 0.0;
  double time = 0.0;                       ///< physical time of the jump [s]
  /// x_minus: the state at `time`; x_plus: the state at the end of the run of frozen elements,
  /// reached at physical time time + clock_advance.
  Eigen::Matrix<double, nx, 1> x_minus, x_plus;
  /// The clock's advance over the run [s]: 0 when the clock stood still in every element; positive
  /// when an element of the run ran it: its last element's last stage (detail::element_frozen:
  /// the element goes on past the end of the impact, e.g. sliding), or an element whose clock
  /// crept while the impact acted (rate below detail::impact_clock_rate). x_plus is then that much
  /// later than the jump, not the post-impact state at `time`.
  double clock_advance = 0.0;
};

/// An element boundary where switching function m changes its active set (alpha rounded to
/// {0, 1/2, 1} differs between the elements on both sides).
struct SwitchPoint {
  double tau = 0.0;   ///< numerical time of the boundary
  double time = 0.0;  ///< physical time there
  int switching_function = 0;  ///< m = 3 i + (0: gap, 1: normal velocity, 2: tangential velocity)
  double alpha_before = 0.0, alpha_after = 0.0;  ///< mean alpha_m over the elements on both sides
};

template <Scene S>
struct TimeFreezingSimulation {
  static constexpr int nx = 2 * S::nq;
  using Point = typename FesdMpcc<S>::Point;
  std::vector<Point> points;  ///< the initial point and every stage point, in numerical time
  std::vector<double> element_lengths;        ///< h of every element, in order
  std::vector<FrozenPhase<nx>> frozen_phases;
  std::vector<SwitchPoint> switch_points;
  /// In physical time, recovered directly (recover_trajectory); also when not converged(), then
  /// only a reading of the unconverged points, not a motion of the scene.
  HybridTrajectory<S> trajectory;
  MpccSolution solution;  ///< the homotopy's result: converged, complementarity, steps, times
  bool converged() const { return solution.converged; }
  /// The state (q, v, t, L, g) at the end of the horizon.
  const auto& final_state() const { return points.back().y; }
};

namespace detail {
/// An element takes part in a frozen phase when its clock stands still (advance below
/// frozen_tolerance * h) or, with n_s >= 2, when its first stage is frozen (Theta < 1e-6): at the
/// end of an impact the element's last stage sits on the switching surfaces (gap = 0, J_n v = 0),
/// where both multipliers vanish and the step function, hence Theta and the clock there, is not
/// determined by the complementarity; the clock then advances by h b_ns Theta_ns inside an
/// element that is an impact (measured: 0.008 s for a dropped mass, a_n = 100). Such an element
/// still ends the frozen run.
/// Also frozen: an element whose clock runs at less than impact_clock_rate of the numerical rate
/// (advance < 1e-4 h) while its velocities jump (some |v| changes by more than 1 % of the largest
/// |v| at its ends, and by more than 1e-6): time-freezing's clock rate is 1 in flight and
/// a_n / (a_n + g)-like in a stance, so such an element is an impact whose clock crept a little
/// (measured: the plank-box's optimal inputs re-integrated on 32 elements per control interval,
/// 480 in all, h ~ 3.1e-3: an element that ran the clock 3.4e-9 s, rate 1.1e-6, above the frozen
/// tolerance's 1e-7, while the box's rate jumped by 1.035 rad/s; read as flowing, its end put a
/// post-impact state among the flow samples, 1.04 from the re-simulation). The velocity jump
/// keeps slow but smooth elements flowing.
inline constexpr double impact_clock_rate = 1e-4;
/// An element of numerical length h <= degenerate_element_length (1 + |tau|) is one FESD collapsed
/// to a point (h's lower bound is 0). recover_trajectory skips it: it has no mode (its step
/// functions are not determined by anything) and no impact fits in it (the auxiliary field
/// changes a velocity by at most a_n s h, 2.5e-8 m/s for a_n = 50 and s = 5), whereas the frozen
/// rule (advance <= frozen_tolerance h) holds trivially there and read it as an impact with no
/// guard and no velocity change (measured: an optimum of the plank-box short landing has two
/// elements of 1.0e-15 and 1.9e-15 at its lift-off; the first was read so). recover_reference
/// keeps such an element as before (frozen when its clock stands, its end a sample): its samples
/// are the re-simulation's input breakpoints, and dropping them turned the plank-box flagship's
/// simulated lift-off into two events 4e-14 s apart (measured); an empty event in the reference
/// costs nothing there.
inline constexpr double degenerate_element_length = 1e-10;
template <int ny, int nsw, int nu>
bool element_degenerate(const std::vector<FesdPoint<ny, nsw, nu>>& pts, int stages, int e) {
  const auto& start = e == 0 ? pts[0] : pts[static_cast<std::size_t>(e * stages)];
  const auto& end = pts[static_cast<std::size_t>((e + 1) * stages)];
  return !(end.tau - start.tau > degenerate_element_length * (1.0 + std::abs(end.tau)));
}
template <int ny, int nsw, int nu>
bool element_frozen(const std::vector<FesdPoint<ny, nsw, nu>>& pts, int stages, int e, double frozen_tolerance) {
  const auto& start = e == 0 ? pts[0] : pts[static_cast<std::size_t>(e * stages)];
  const auto& end = pts[static_cast<std::size_t>((e + 1) * stages)];
  const double h = end.tau - start.tau;
  if (!(h > 0.0)) return false;
  constexpr int clock = ny - 2 - nsw / 3;  // y = (q, v, t, L, g) with nc = nsw / 3 integrated gaps
  const double advance = end.y[clock] - start.y[clock];
  if (advance <= frozen_tolerance * h) return true;
  if (stages >= 2 && pts[static_cast<std::size_t>(1 + e * stages)].ode_weight < 1e-6) return true;
  if (advance < impact_clock_rate * h) {
    constexpr int nv = (clock) / 2;  // y = (q, v, ...) with nq = nv
    const auto v0 = start.y.template segment<nv>(nv), v1 = end.y.template segment<nv>(nv);
    const double jump = (v1 - v0).cwiseAbs().maxCoeff();
    return jump > 1e-6 && jump > 1e-2 * std::max(v0.cwiseAbs().maxCoeff(), v1.cwiseAbs().maxCoeff());
  }
  return false;
}
}  // namespace detail

namespace detail {
/// Reads frozen phases and switch points off a FESD solution (see TimeFreezingSimulation).
/// Frozen elements: detail::element_frozen.
template <int ny, int nsw, int nu, int nx>
void read_events(const std::vector<FesdPoint<ny, nsw, nu>>& pts, int stages, std::vector<double>& lengths,
                 std::vector<FrozenPhase<nx>>& frozen, std::vector<SwitchPoint>& switches, double frozen_tolerance = 1e-7) {
  const int clock = nx;
  const int elements = static_cast<int>((pts.size() - 1) / stages);
  auto start_of = [&](int e) -> const FesdPoint<ny, nsw, nu>& { return e == 0 ? pts[0] : pts[e * stages]; };
  auto end_of = [&](int e) -> const FesdPoint<ny, nsw, nu>& { return pts[(e + 1) * stages]; };
  std::vector<bool> is_frozen(elements);
  for (int e = 0; e < elements; ++e) {
    const double h = end_of(e).tau - start_of(e).tau;
    lengths.push_back(h);
    is_frozen[e] = element_frozen(pts, stages, e, frozen_tolerance);
  }
  for (int e = 0; e < elements;) {
    if (!is_frozen[e]) {
      ++e;
      continue;
    }
    int f = e;
    while (f + 1 < elements && is_frozen[f + 1]) ++f;
    FrozenPhase<nx> p;
    p.tau_begin = start_of(e).tau;
    p.tau_end = end_of(f).tau;
    p.time = start_of(e).y[clock];
    p.x_minus = start_of(e).y.template head<nx>();
    p.x_plus = end_of(f).y.template head<nx>();
    p.clock_advance = end_of(f).y[clock] - p.time;
    frozen.push_back(p);
    e = f + 1;
  }
  auto mean_alpha = [&](int e, int m) {
    double s = 0.0;
    for (int r = 0; r < stages; ++r) s += pts[1 + e * stages + r].alpha[m];
    return s / stages;
  };
  auto rounded = [](double a) { return a > 1.0 - 1e-6 ? 2 : (a < 1e-6 ? 0 : 1); };
  for (int e = 0; e + 1 < elements; ++e)
    for (int m = 0; m < nsw; ++m) {
      const double a = mean_alpha(e, m), b = mean_alpha(e + 1, m);
      if (rounded(a) != rounded(b)) switches.push_back({end_of(e).tau, end_of(e).y[clock], m, a, b});
    }
}
}  // namespace detail

/// Recovers the physical-time reference from a discrete time-freezing solution (time-freezing
/// Theorem 5): the samples are the element boundaries at their physical times t (the clock
/// state; interior Radau stages are left out: with a_12 < 0 their clocks need not increase); a
/// run of frozen elements (detail::element_frozen) is removed and becomes an
/// event: the sample at its start (x-) and at its end (x+) share the event's time, x- first, and
/// the time is listed in event_times. When the run's clock advanced (its last element went on
/// past the end of the impact: FrozenPhase::clock_advance > frozen_tolerance * h), the end
/// sample is NOT the post-impact state at the event time: it keeps its own clock time, after
/// the event, and the event has no x+ sample (ImportedReference allows that). Stamping it with
/// the event time instead put a position jump into the reference (the point-mass OCP of
/// scenes/time_freezing_examples.hpp: the end sample 0.053 s of sliding, 0.087 m, after the
/// impact) and its re-simulation 0.09 away. Inputs are the applied inputs at the samples; at every
/// control-interval boundary the sample is repeated with the next interval's input, so the
/// right-continuous interpolation of ImportedReference::input reproduces the piecewise-constant
/// control exactly. Polish the result (hybrid/reference/resimulation.hpp: polish) to re-simulate
/// it with the event-driven simulator and to obtain the HybridTrajectory that the sensitivity
/// analysis takes. Throws InvalidArgument if points has no stage point, stages is not 1, 2 or 3, or
/// a point's recorded stage (FesdPoint::stage) does not match its position for that n_s.
template <Scene S, int ny, int nsw, int nu>
ImportedReference<S> recover_reference(const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       double frozen_tolerance = 1e-7) {
  constexpr int nx = 2 * S::nq;
  SALTUS_REQUIRE(stages >= 1 && points.size() >= 1 + static_cast<std::size_t>(stages) &&
                     (points.size() - 1) % static_cast<std::size_t>(stages) == 0,
                 "recover_reference: expected the initial point and n_s points per element, got ", points.size(),
                 " points for n_s = ", stages);
  SALTUS_REQUIRE(stages <= 3, "recover_reference: n_s must be 1, 2 or 3 (Radau IIA), got ", stages);
  // The points record their stage: a wrong n_s would pair stages of different elements.
  for (std::size_t k = 1; k < points.size(); ++k)
    SALTUS_REQUIRE(points[k].stage == static_cast<int>((k - 1) % static_cast<std::size_t>(stages)),
                   "recover_reference: point ", k, " is stage ", points[k].stage, " of its element, but n_s = ", stages,
                   " makes it stage ", (k - 1) % static_cast<std::size_t>(stages));
  ImportedReference<S> ref;
  // Every sample's segment is written out: a frozen run that starts on a control-interval
  // boundary has two pre-event samples at the event time (x- and its repeat with the next
  // interval's input), which ImportedReference::segment_of would otherwise count as x- and x+.
  int segment = 0;
  auto add = [&](const FesdPoint<ny, nsw, nu>& p) {
    ref.t.push_back(p.y[nx]);
    ref.x.push_back(p.y.template head<nx>());
    ref.u.push_back(p.u);
    ref.segment.push_back(segment);
  };
  const int elements = static_cast<int>((points.size() - 1) / stages);
  auto end_of = [&](int e) -> const FesdPoint<ny, nsw, nu>& { return points[static_cast<std::size_t>((e + 1) * stages)]; };
  auto frozen = [&](int e) { return detail::element_frozen(points, stages, e, frozen_tolerance); };
  add(points[0]);
  for (int e = 0; e < elements;) {
    if (frozen(e)) {
      int f = e;
      while (f + 1 < elements && frozen(f + 1)) ++f;
      // x- is the last sample (the start of the run); x+ at the same time, unless the clock ran
      // inside the run (then the end sample stays at its own, later, time).
      ref.event_times.push_back(ref.t.back());
      FesdPoint<ny, nsw, nu> plus = end_of(f);
      const double h_last = end_of(f).tau - points[static_cast<std::size_t>(f == 0 ? 0 : f * stages)].tau;
      if (plus.y[nx] - ref.t.back() <= frozen_tolerance * h_last) plus.y[nx] = ref.t.back();
      ++segment;
      add(plus);
      e = f + 1;
    } else {
      add(end_of(e));
      ++e;
    }
    // A control-interval boundary: repeat the sample with the next interval's input.
    if (e < elements && points[static_cast<std::size_t>(1 + e * stages)].interval != end_of(e - 1).interval) {
      FesdPoint<ny, nsw, nu> next = end_of(e - 1);
      next.u = points[static_cast<std::size_t>(1 + e * stages)].u;
      add(next);
    }
  }
  return ref;
}

/// Tolerances of recover_trajectory.
struct TrajectoryRecoveryOptions {
  /// A contact is closed at a point where its gap is <= gap_tolerance [m] and its normal velocity
  /// |J_n v| <= velocity_tolerance [m/s] (a point that reaches the surface at a negative J_n v, the
  /// end of a flight, is not closed); a closed contact with friction slips where |J_t v| >
  /// velocity_tolerance (with that sign) and sticks where not. Both > 0. Sized above the
  /// discretisation's residual drift (a frozen phase's gap of -1.6e-5 without the contact-side
  /// selection, fesd.hpp) and below the motions' own scales.
  double gap_tolerance = 1e-4;
  double velocity_tolerance = 1e-4;
  /// Elements whose clock advances by at most frozen_tolerance * h are frozen (as recover_reference);
  /// so are those detail::element_frozen adds (a frozen first stage, a crept clock with a velocity
  /// jump).
  double frozen_tolerance = 1e-7;
  /// In a flowing element, a contact that the state calls closed (above) is read as open when its
  /// closing weight w = (1 - alpha_gap)(1 - alpha_vn) (alpha_gap, alpha_vn: the step functions of
  /// its gap and J_n v switching functions, FesdPoint::alpha[3 i], [3 i + 1]) at the element's
  /// last interior stage point (recover_trajectory: "Modes"; TimeFreezingSystem::closing_weight)
  /// is below closing_weight_tolerance (dimensionless, in (0, 1)): the auxiliary dynamics then
  /// carry no force, as after a tangential lift-off, where the state stays within the tolerances
  /// above (J_n v = g (t - 1.5)^2 in the guiding example, Example 3) while the weight falls
  /// through zero transversally (w = 1 - 1 / (2 (2 - t)) there). Sized above the weights that a converged
  /// homotopy leaves in the degenerate elements next to such a switch (measured: up to 3e-6 at a
  /// complementarity of 1e-14, Example 3 at n_s = 2 with 1,120 elements). Points outside flowing
  /// elements (the first point, and x+ of a frozen run at the end of the horizon) and the search
  /// for x+ of an absorbed impact are read by the state alone: their step functions say nothing
  /// about a force (the first point's are a placeholder, 0.5).
  double closing_weight_tolerance = 1e-4;
};

/// Recovers the physical-time HybridTrajectory of a discrete time-freezing solution (time-freezing
/// Theorem 5), without re-simulating it: the frozen intervals are removed and every run of frozen
/// elements becomes an impact event; the contact modes are read off the states; a mode change
/// between two flowing elements becomes an event without impact. Compare polish() (resimulation.hpp),
/// which re-simulates recover_reference's samples with the event-driven simulator instead.
///
/// - Modes: per flowing element and contact, from the switching functions at the element's last
///   interior stage point (c_r < 1: Radau's end point is the next element's start and lies on the
///   switching surface when a switch is there; n_s = 1 has only the end point) and the contact's
///   closing weight there, with the tolerances of TrajectoryRecoveryOptions. A frictionless
///   contact (or mu = 0) that is closed is ContactState::slip(0), as the simulator stores it. A
///   switch inside an element (the grid did not locate it, e.g. a slip-stick with
///   velocity_switch_detection = false) appears at the element boundary next to it.
/// - Segments: one per run of flowing elements with the same mode. Dense output: per element the
///   polynomial through its start point and its n_s stage points, in physical time (degree n_s;
///   exact where the clock runs at a constant rate: Theta = 1). Where the stage clocks are not
///   strictly increasing (Radau's interior stages under a nearly frozen clock) the piece is the
///   straight line between the element's end points.
/// - Impact events (runs of frozen elements): at the clock time of the run's start, x- its start
///   state and x+ its end state, mode_before the previous segment's mode and mode_after the next
///   one's; one transition with impact = true and a Touchdown guard for every contact that was
///   open before and approaching (gap <= gap_tolerance, J_n v < -velocity_tolerance at x-): both
///   corners of a flat landing. The transition's impulse_mode names the contacts whose closing
///   weight (1 - alpha_gap)(1 - alpha_vn) reached 1/2 in the run, with the impact solver's roles
///   (stick: frictionless, or at tangential rest after the impact; slip: along the sign of J_t v
///   at x+), so that jump_gains() (sensitivity/jump_gain.hpp) can differentiate its jump map; the
///   impulse itself is not recovered (left zero). A run without an approaching open contact has no
///   guard (Transition::guards empty). When the run's clock advanced (FrozenPhase::clock_advance:
///   its last element went on past the end of the impact), x+ is the state that much later and
///   the next segment's first piece holds x+ constant over the advance: the trajectory is off by
///   the motion over clock_advance there. The same when the run ends before the impact does (a
///   contact with gap <= gap_tolerance still approaching, J_n v < -velocity_tolerance, at the
///   run's end: the last part of the impact was resolved by the next, flowing element, which
///   velocity_switch_detection = false allows; the plank-box flagship's landing): x+ is the first
///   stage point of that element from which on no such contact approaches, held over its clock
///   advance.
/// - Mode changes without impact: x- = x+ = the boundary state; guards per contact: Touchdown
///   (open -> closed without a frozen run: a touchdown at zero normal velocity), Release (closed ->
///   open), Stop (slip -> stick), SlipOnset (stick -> slip, or a reversal of the slip direction).
/// - Absorbed impacts: a touchdown at J_n v(x-) < -velocity_tolerance that is not a frozen run is
///   an impact the discretisation absorbed into a flowing element (the clock ran through it).
///   That is the rule, not the exception, under FesdOptions::velocity_switch_detection = false
///   (the flagship OCPs' setting): the end of an impact is a switch of J_n v, which the grid then
///   does not locate, so an impact shorter than its element ends inside it (the plank-box flat
///   landing: J_n v = -1.04 m/s against a_n = 50 lasts about 1.04 / 50 = 0.02 of numerical time at
///   speed of time 1, less at s > 1, in elements of h0 = 0.05). It is read as an impact event at
///   the element's start: x- there, x+ the state at the element's first stage point from which on
///   every struck contact is closed, held over the clock advance to it (as for a frozen run's
///   advance), guards Touchdown for the struck contacts (and the mode changes of the others),
///   impulse_mode for the struck contacts. x+ is then off by the motion over that advance, and a
///   jump gain of it is refused unless x+ is the impact law's post-impact state to 1e-9.
/// - The input law u(t) is recover_reference's (ImportedReference::input: linear between the
///   samples, right-continuous at control-interval boundaries), whatever x and the mode.
/// The trajectory is a reading of the points whether or not their homotopy converged: the one of
/// an unconverged solution (complementarity above tolerance) is not a motion of the scene (events
/// off, states below the surface) and its status still says Completed; check converged() first.
/// Throws InvalidArgument as recover_reference does (n_s outside 1..3, points whose recorded stage
/// does not match n_s), for tolerances that are not finite and > 0, and for a
/// closing_weight_tolerance outside (0, 1).
template <Scene S, int ny, int nsw, int nu>
HybridTrajectory<S> recover_trajectory(const TimeFreezingSystem<S>& system,
                                       const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       const TrajectoryRecoveryOptions& options = {}) {
  constexpr int nq = S::nq, nx = 2 * S::nq, nc = S::nc;
  using Point = FesdPoint<ny, nsw, nu>;
  using ModeT = Mode<nc>;
  using State = VecT<double, nx>;
  static_assert(ny == nx + 2 + nc && nsw == 3 * nc, "recover_trajectory: points of another scene");
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  SALTUS_REQUIRE(positive(options.gap_tolerance) && positive(options.velocity_tolerance) &&
                     positive(options.frozen_tolerance),
                 "recover_trajectory: the tolerances must be finite and > 0, got gap ", options.gap_tolerance,
                 ", velocity ", options.velocity_tolerance, ", frozen ", options.frozen_tolerance);
  SALTUS_REQUIRE(positive(options.closing_weight_tolerance) && options.closing_weight_tolerance < 1.0,
                 "recover_trajectory: closing_weight_tolerance must be in (0, 1), got ", options.closing_weight_tolerance);
  const ImportedReference<S> samples = recover_reference<S>(points, stages, options.frozen_tolerance);
  const int elements = static_cast<int>((points.size() - 1) / static_cast<std::size_t>(stages));
  auto start_of = [&](int e) -> const Point& { return points[static_cast<std::size_t>(e == 0 ? 0 : e * stages)]; };
  auto stage_of = [&](int e, int r) -> const Point& { return points[static_cast<std::size_t>(1 + e * stages + r)]; };
  auto end_of = [&](int e) -> const Point& { return stage_of(e, stages - 1); };
  auto state = [](const Point& p) { return State(p.y.template head<nx>()); };
  auto clock = [](const Point& p) { return p.y[nx]; };
  auto switching = [&](const Point& p) {
    return system.template switching_functions<double>(Vec<nq>(p.y.template head<nq>()),
                                                       Vec<nq>(p.y.template segment<nq>(nq)));
  };
  const double gap_tol = options.gap_tolerance, vel_tol = options.velocity_tolerance;
  auto frictional = [&](int i) { return system.has_friction(i) && system.scene().contact(i).mu > 0.0; };
  // One contact's state at one point: 0 open, 1 stick, 2 slip+, 3 slip-, 4 closed frictionless.
  auto contact_class = [&](const Vec<nsw>& c, int i) {
    if (!(c[3 * i] <= gap_tol && std::abs(c[3 * i + 1]) <= vel_tol)) return 0;  // open, or approaching
    if (!frictional(i)) return 4;
    const double vt = c[3 * i + 2];
    return std::abs(vt) <= vel_tol ? 1 : (vt > 0.0 ? 2 : 3);
  };
  auto to_state = [](int cls) {
    switch (cls) {
      case 1: return ContactState::stick();
      case 2: return ContactState::slip_planar(1);
      case 3: return ContactState::slip_planar(-1);
      case 4: return ContactState::slip(Eigen::Vector2d::Zero());
      default: return ContactState::open();
    }
  };
  // The element's mode from its last interior stage point (the end point is the next element's
  // start and sits on the switching surface when the switch is there; n_s = 1 has only the end
  // point): a switch inside the element is read at its end. A contact closed by its state but
  // without closing weight there carries no force and is open (closing_weight_tolerance).
  auto mode_of_element = [&](int e) {
    ModeT m;
    const Point& p = stage_of(e, stages >= 2 ? stages - 2 : 0);
    const Vec<nsw> c = switching(p);
    for (int i = 0; i < nc; ++i) {
      const double weight = TimeFreezingSystem<S>::template closing_weight<double>(p.alpha, i);
      m[i] = to_state(weight < options.closing_weight_tolerance ? 0 : contact_class(c, i));
    }
    return m;
  };
  auto mode_at = [&](const Point& p) {
    ModeT m;
    const Vec<nsw> c = switching(p);
    for (int i = 0; i < nc; ++i) m[i] = to_state(contact_class(c, i));
    return m;
  };
  auto degenerate = [&](int e) { return detail::element_degenerate(points, stages, e); };
  auto frozen = [&](int e) { return !degenerate(e) && detail::element_frozen(points, stages, e, options.frozen_tolerance); };
  // The earliest stage r <= last of element e such that `holds` (of the switching functions) is
  // true at every stage r .. last; -1 when it is false at `last`.
  auto start_of_trailing_run = [&](int e, int last, const auto& holds) {
    int first = -1;
    for (int r = last; r >= 0 && holds(switching(stage_of(e, r))); --r) first = r;
    return first;
  };
  // How contact i took an impulse, as the impact solver labels it: stick for a frictionless contact
  // or a tangential rest after the impact, else slip along J_t v+ (c_plus: the switching
  // functions at x+).
  auto impulse_role = [&](int i, const Vec<nsw>& c_plus) {
    const double vt = c_plus[3 * i + 2];
    if (!frictional(i) || std::abs(vt) <= vel_tol) return ImpulseMode{ImpulseRole::Stick, Eigen::Vector2d::Zero()};
    return ImpulseMode{ImpulseRole::Slip, Eigen::Vector2d(vt > 0.0 ? 1.0 : -1.0, 0.0)};
  };
  // The piece of element e in physical time, through its points from `first` on (-1: the
  // element's start point, r >= 0: stage r) to its end.
  auto piece_of = [&](int e, int first = -1) {
    PolynomialPiece<nx> p;
    const int n = stages - first;  // the number of nodes, 2 .. n_s + 1 (1 when first is the end)
    std::array<double, 4> t{};
    std::array<State, 4> x;
    for (int a = 0; a < n; ++a) {
      const Point& node = first + a < 0 ? start_of(e) : stage_of(e, first + a);
      t[static_cast<std::size_t>(a)] = clock(node);
      x[static_cast<std::size_t>(a)] = state(node);
    }
    p.t0 = p.t_ref = t[0];
    p.t1 = t[static_cast<std::size_t>(n - 1)];
    p.h = p.t1 - p.t0;
    bool increasing = p.h > 0.0;
    for (int r = 1; r < n && increasing; ++r)
      increasing = t[static_cast<std::size_t>(r)] - t[static_cast<std::size_t>(r - 1)] > 1e-12 * (1.0 + std::abs(p.t0));
    if (!increasing) {
      p.degree = 1;
      p.c.col(0) = x[0];
      p.c.col(1) = x[static_cast<std::size_t>(n - 1)] - x[0];
      if (!(p.h > 0.0)) p.h = 1.0;  // a zero-length piece: only its value at t0 is ever read
      return p;
    }
    // Interpolation in theta = (t - t0) / h at the n nodes: the Vandermonde system, n <= 4 (not a
    // hot path: once per element of a recovered solution).
    Eigen::MatrixXd v(n, n), rhs(n, nx);
    for (int a = 0; a < n; ++a) {
      const double th = (t[static_cast<std::size_t>(a)] - p.t0) / p.h;
      double pw = 1.0;
      for (int b = 0; b < n; ++b, pw *= th) v(a, b) = pw;
      rhs.row(a) = x[static_cast<std::size_t>(a)].transpose();
    }
    const Eigen::MatrixXd coef = v.fullPivLu().solve(rhs);
    p.degree = n - 1;
    for (int b = 0; b < n; ++b) p.c.col(b) = coef.row(b).transpose();
    return p;
  };

  HybridTrajectory<S> traj;
  traj.input = [samples](double t, const State&, const ModeT&) { return samples.input(t); };
  Segment<S> seg;
  seg.t_begin = clock(points[0]);
  seg.t_end = seg.t_begin;
  bool seg_has_mode = false;
  auto close_segment = [&](double t_end) {
    seg.t_end = t_end;
    traj.segments.push_back(seg);
    seg = Segment<S>{};
    seg.t_begin = t_end;
    seg.t_end = t_end;
    seg_has_mode = false;
  };
  auto add_event = [&](double t, const State& xm, const State& xp, const ModeT& before, const ModeT& after,
                       std::vector<Guard> guards, bool impact) {
    Event<S> ev;
    ev.t = t;
    ev.x_minus = xm;
    ev.x_plus = xp;
    ev.mode_before = before;
    ev.mode_after = after;
    Transition<S> tr;
    tr.guards = std::move(guards);
    tr.mode_before = before;
    tr.mode_after = after;
    tr.x_before = xm;
    tr.x_after = xp;
    tr.impact = impact;
    ev.transitions.push_back(std::move(tr));
    traj.events.push_back(std::move(ev));
  };
  auto changes = [&](const ModeT& before, const ModeT& after) {
    std::vector<Guard> guards;
    for (int i = 0; i < nc; ++i) {
      if (before[i] == after[i]) continue;
      if (!before[i].closed()) guards.push_back({i, GuardKind::Touchdown});
      else if (!after[i].closed()) guards.push_back({i, GuardKind::Release});
      else if (after[i].mode == ContactMode::Stick) guards.push_back({i, GuardKind::Stop});
      else guards.push_back({i, GuardKind::SlipOnset});
    }
    return guards;
  };
  // Where the clock advanced past an impact's time t before its x+ (at `plus`): x+ held constant
  // over [t, clock(plus)] (see the docstring).
  auto hold_over_advance = [&](double t, const Point& plus) {
    if (!(clock(plus) > t)) return;
    PolynomialPiece<nx> hold;
    hold.t0 = hold.t_ref = t;
    hold.t1 = clock(plus);
    hold.h = hold.t1 - t;
    hold.degree = 0;
    hold.c.col(0) = state(plus);
    seg.x.append(hold);
  };
  ModeT current = mode_at(points[0]);
  for (int e = 0; e < elements;) {
    if (frozen(e)) {
      int f = e;
      while (f + 1 < elements && frozen(f + 1)) ++f;
      const Point& minus = start_of(e);
      const double t = clock(minus);
      // An impact that the run did not finish (docstring: a contact still approaching at the run's
      // end, J_n v < -velocity_tolerance, ends inside the next, flowing element): x+ is that
      // element's first stage point from which on no such contact approaches any more.
      int tail = -1;  // the stage of element f + 1 that holds x+, or -1: the run's end
      if (f + 1 < elements) {
        const Vec<nsw> c_end = switching(end_of(f));
        std::vector<int> approaching;
        for (int i = 0; i < nc; ++i)
          if (c_end[3 * i] <= gap_tol && c_end[3 * i + 1] < -vel_tol) approaching.push_back(i);
        if (!approaching.empty())
          tail = start_of_trailing_run(f + 1, stages - 1, [&](const Vec<nsw>& cr) {
            bool done = true;
            for (int i : approaching) done = done && cr[3 * i + 1] >= -vel_tol;
            return done;
          });
      }
      const Point& plus = tail >= 0 ? stage_of(f + 1, tail) : end_of(f);
      int next = f + 1;  // the next element with a length (collapsed ones say nothing of a mode)
      while (next < elements && degenerate(next)) ++next;
      const ModeT after = next < elements ? mode_of_element(next) : mode_at(plus);
      const Vec<nsw> c = switching(minus);
      std::vector<Guard> guards;
      for (int i = 0; i < nc; ++i)
        if (!current[i].closed() && c[3 * i] <= gap_tol && c[3 * i + 1] < -vel_tol) guards.push_back({i, GuardKind::Touchdown});
      // Who took an impulse: a contact whose closing weight (1 - alpha_gap)(1 - alpha_vn) reached
      // 1/2 at a stage point of the run; how: impulse_role.
      ImpactMode<nc> impulse;
      const Vec<nsw> c_plus = switching(plus);
      for (int i = 0; i < nc; ++i) {
        double closing = 0.0;
        for (int g = e; g <= f; ++g)
          for (int r = 0; r < stages; ++r) {
            const auto& a = stage_of(g, r).alpha;
            closing = std::max(closing, TimeFreezingSystem<S>::template closing_weight<double>(a, i));
          }
        if (closing >= 0.5) impulse[i] = impulse_role(i, c_plus);
      }
      if (!seg_has_mode) seg.mode = current;
      close_segment(t);
      add_event(t, state(minus), state(plus), current, after, std::move(guards), true);
      traj.events.back().transitions.back().impulse_mode = impulse;
      current = after;
      seg.mode = after;
      seg_has_mode = true;
      hold_over_advance(t, plus);
      e = f + 1;
      if (tail >= 0) {  // the impact's tail: element f + 1 from x+ on
        if (tail < stages - 1) seg.x.append(piece_of(e, tail));
        ++e;
      }
      continue;
    }
    if (degenerate(e)) {  // collapsed to a point by FESD: no mode, no piece (detail::element_degenerate)
      ++e;
      continue;
    }
    const ModeT m = mode_of_element(e);
    if (!seg_has_mode) {  // the first element (after an impact the next element's mode is set)
      seg.mode = m;
      seg_has_mode = true;
    } else if (!(m == seg.mode)) {
      const double t = clock(start_of(e));
      // An impact absorbed into this flowing element (docstring): contacts open before, closed in
      // this element's mode and approaching at its start. Read as an impact at the element's start
      // with x+ at its first stage point where they are all closed, held over the clock advance.
      const Vec<nsw> c = switching(start_of(e));
      std::vector<int> struck;
      for (int i = 0; i < nc; ++i)
        if (!current[i].closed() && m[i].closed() && c[3 * i + 1] < -vel_tol) struck.push_back(i);
      if (!struck.empty()) {
        // From the stage that decided the element's mode (closed for them) back to the earliest
        // stage of a closed run.
        const int deciding = stages >= 2 ? stages - 2 : 0;
        int first_closed = start_of_trailing_run(e, deciding, [&](const Vec<nsw>& cr) {
          bool closed = true;
          for (int i : struck) closed = closed && contact_class(cr, i) != 0;
          return closed;
        });
        if (first_closed < 0) first_closed = deciding;
        const Point& plus = stage_of(e, first_closed);
        std::vector<Guard> guards = changes(current, m);
        ImpactMode<nc> impulse;
        const Vec<nsw> c_plus = switching(plus);
        for (int i : struck) impulse[i] = impulse_role(i, c_plus);
        close_segment(t);
        add_event(t, state(start_of(e)), state(plus), current, m, std::move(guards), true);
        traj.events.back().transitions.back().impulse_mode = impulse;
        seg.mode = m;
        seg_has_mode = true;
        current = m;
        hold_over_advance(t, plus);
        if (first_closed < stages - 1) seg.x.append(piece_of(e, first_closed));
        ++e;
        continue;
      }
      close_segment(t);
      add_event(t, state(start_of(e)), state(start_of(e)), current, m, changes(current, m), false);
      seg.mode = m;
      seg_has_mode = true;
    }
    current = m;
    seg.x.append(piece_of(e));
    ++e;
  }
  if (!seg_has_mode) seg.mode = current;
  seg.t_end = std::max(seg.t_begin, clock(points.back()));
  traj.segments.push_back(seg);
  traj.set_final_state(state(points.back()));
  traj.status = SimulationStatus::Completed;
  return traj;
}

/// How simulate_time_freezing splits the horizon into MPCCs.
enum class SimulationSplit {
  PerControlInterval,  ///< one MPCC per control interval, each from the previous one's end (NOSNOC's integrator)
  WholeHorizon,        ///< one MPCC over all control intervals
};

/// Simulates the time-freezing system of `system` from (q0, v0) at physical time
/// fesd.initial_time over the numerical horizon fesd.horizon under the input law of `law` (an
/// object with `template <class T> VecT<T, nu> input(const T& t, const VecT<T, nu>& decision) const`,
/// t the physical time; NoObjective applies u = 0).
/// fesd.clock, speed_of_time_max and the control bounds are overridden (no clock constraint,
/// s = 1, decisions fixed at 0). The input law must be smooth inside each control interval (a kink
/// in time belongs on a control-interval boundary, where the grid is fixed).
/// PerControlInterval (the default) solves N small MPCCs in sequence; the cross-complementarity
/// across their boundaries is then not imposed (the first element of each interval has no
/// previous end point), as in NOSNOC's integrator.
/// With solver.progress set, a line "simulate_time_freezing: control interval k of N" precedes each
/// interval's homotopy lines (PerControlInterval).
/// Returns the result whether or not every homotopy converged: converged() is true only when all
/// did; solution holds the totals (iterations, seconds; complementarity the largest; steps all).
/// Throws InvalidArgument for bad options or initial states, as FesdMpcc and solve_mpcc do.
template <Scene S, class InputLaw = NoObjective>
TimeFreezingSimulation<S> simulate_time_freezing(const TimeFreezingSystem<S>& system, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, FesdOptions fesd, const InputLaw& law = {},
                                                 const MpccSolverOptions& solver = {},
                                                 SimulationSplit split = SimulationSplit::PerControlInterval) {
  constexpr int nq = S::nq;
  // Checked here too: the split below divides by them before FesdMpcc would see them.
  SALTUS_REQUIRE(fesd.control_intervals >= 1, "FESD: control_intervals must be >= 1, got ", fesd.control_intervals);
  SALTUS_REQUIRE(std::isfinite(fesd.horizon) && fesd.horizon > 0.0, "FESD: the numerical horizon must be > 0, got ",
                 fesd.horizon);
  fesd.clock = ClockConstraint::None;
  fesd.speed_of_time_max = 1.0;
  fesd.speed_of_time_weight = 0.0;
  fesd.control_lower = Eigen::VectorXd::Zero(S::nu);
  fesd.control_upper = Eigen::VectorXd::Zero(S::nu);
  TimeFreezingSimulation<S> out;
  const int pieces = split == SimulationSplit::WholeHorizon ? 1 : fesd.control_intervals;
  FesdOptions piece = fesd;
  if (pieces > 1) {
    piece.control_intervals = 1;
    piece.horizon = fesd.horizon / fesd.control_intervals;
  }
  Vec<nq> q = q0, v = v0;
  double tau0 = 0.0, cost0 = 0.0;
  out.solution.converged = true;
  for (int k = 0; k < pieces; ++k) {
    // Which MPCC the progress lines that follow belong to (each restarts at step 0).
    if (solver.progress && pieces > 1)
      *solver.progress << "simulate_time_freezing: control interval " << k + 1 << " of " << pieces << "\n";
    const FesdMpcc<S, InputLaw> problem(system, law, q, v, piece);
    MpccSolution sol = solve_mpcc(problem, solver);
    auto pts = problem.points(sol.x);
    for (auto& p : pts) {
      p.tau += tau0;
      p.interval += k;
      p.y[TimeFreezingSystem<S>::cost_index] += cost0;
    }
    out.points.insert(out.points.end(), pts.begin() + (k == 0 ? 0 : 1), pts.end());
    const auto& end = out.points.back().y;
    q = end.template head<nq>();
    v = end.template segment<nq>(nq);
    piece.initial_time = end[TimeFreezingSystem<S>::clock_index];
    // The user's initial state was checked; a later interval starts where the previous one
    // ended, which may be below a contact by the discretisation's own drift (a frozen phase's gap
    // of -1e-5, see the note): not a user error.
    piece.gap_tolerance = std::numeric_limits<double>::infinity();
    cost0 = end[TimeFreezingSystem<S>::cost_index];
    tau0 += piece.horizon;
    // Totals.
    MpccSolution& t = out.solution;
    t.converged = t.converged && sol.converged;
    if (!sol.converged && t.message.empty()) t.message = "control interval " + std::to_string(k) + ": " + sol.message;
    if (sol.complementarity >= t.complementarity) {
      t.complementarity = sol.complementarity;
      t.worst_pair = "interval " + std::to_string(k) + ": " + sol.worst_pair;
    }
    t.constraint_violation = std::max(t.constraint_violation, sol.constraint_violation);
    t.ipopt_iterations += sol.ipopt_iterations;
    t.seconds += sol.seconds;
    t.objective += sol.objective;
    t.steps.insert(t.steps.end(), sol.steps.begin(), sol.steps.end());
    if (pieces == 1) t.x = sol.x;
  }
  if (out.solution.converged) out.solution.message = "every homotopy converged";
  detail::read_events<FesdMpcc<S>::ny, FesdMpcc<S>::nsw, S::nu, 2 * S::nq>(out.points, fesd.stages, out.element_lengths,
                                                                          out.frozen_phases, out.switch_points);
  out.trajectory = recover_trajectory<S>(system, out.points, fesd.stages);
  return out;
}

/// The result of solve_time_freezing_ocp.
template <Scene S>
struct TimeFreezingOcpResult {
  static constexpr int nx = 2 * S::nq;
  using Point = typename FesdMpcc<S>::Point;
  MpccSolution solution;       ///< converged, complementarity, objective, steps, iterations, seconds
  std::vector<Point> points;   ///< the discrete solution in numerical time
  std::vector<double> element_lengths;
  std::vector<FrozenPhase<nx>> frozen_phases;  ///< the impacts
  std::vector<SwitchPoint> switch_points;      ///< touchdowns, lift-offs, slip-stick
  ImportedReference<S> reference;              ///< recovered in physical time (recover_reference)
  /// Recovered in physical time (recover_trajectory); when not converged(), only a reading of the
  /// unconverged points, not a motion of the scene.
  HybridTrajectory<S> trajectory;
  /// solve_time_freezing_ocp_by_continuation: one relaxed NLP per continuation stage, in order
  /// (their iterations and seconds are included in solution.ipopt_iterations and seconds).
  std::vector<MpccHomotopyStep> continuation_steps;
  bool converged() const { return solution.converged; }
};

/// The physical time [s] that event `e` of a trajectory from recover_trajectory reads its x+ at:
/// the event's time, or later where the discretisation's clock ran on past the impact's instant
/// before the impact ended (recover_trajectory's docstring: x+ is held constant over that
/// advance, as the first piece of the next segment). Throws InvalidArgument for e out of range.
template <Scene S>
double x_plus_time(const HybridTrajectory<S>& traj, std::size_t e) {
  SALTUS_REQUIRE(e < traj.events.size(), "x_plus_time: event ", e, " of ", traj.events.size());
  const double t = traj.events[e].t;
  for (const Segment<S>& seg : traj.segments)
    if (seg.t_begin == t && !seg.x.empty()) {
      const auto& first = seg.x.pieces().front();
      if (first.degree == 0 && first.t0 == t && first.t1 > t && first.c.col(0) == traj.events[e].x_plus) return first.t1;
    }
  return t;
}

namespace detail {
// align_impact_samples' first part (its docstring): recover_trajectory's impacts that
// recover_reference has no event for, added to the reference.
template <Scene S>
void add_absorbed_impacts(ImportedReference<S>& ref, const HybridTrajectory<S>& traj) {
  if (ref.segment.size() != ref.t.size()) return;  // recover_reference writes every segment
  for (std::size_t e = 0; e < traj.events.size(); ++e) {
    if (!traj.events[e].impact()) continue;
    const double t = traj.events[e].t;
    const auto same = [t](double s) { return std::abs(s - t) <= 1e-12 * (1.0 + std::abs(t)); };
    if (std::any_of(ref.event_times.begin(), ref.event_times.end(), same)) continue;
    // x-: the last sample at the event's time
    std::size_t j = ref.size();
    for (std::size_t k = 0; k < ref.size(); ++k)
      if (same(ref.t[k])) j = k;
    if (j + 1 >= ref.size()) continue;  // no sample after it: nothing to mark as post-impact
    const double t_plus = x_plus_time(traj, e);
    std::size_t plus = j + 1;
    if (t_plus < ref.t[j + 1]) {  // x+ lies inside the element: a sample of its own
      ref.t.insert(ref.t.begin() + static_cast<std::ptrdiff_t>(plus), t_plus);
      ref.x.insert(ref.x.begin() + static_cast<std::ptrdiff_t>(plus), traj.events[e].x_plus);
      const typename ImportedReference<S>::Input u = ref.u[plus];
      const int segment = ref.segment[j];
      ref.u.insert(ref.u.begin() + static_cast<std::ptrdiff_t>(plus), u);
      ref.segment.insert(ref.segment.begin() + static_cast<std::ptrdiff_t>(plus), segment);
    }
    for (std::size_t k = plus; k < ref.size(); ++k) ++ref.segment[k];
    ref.event_times.insert(std::upper_bound(ref.event_times.begin(), ref.event_times.end(), ref.t[j]), ref.t[j]);
  }
}

/// The x+ sample of each of recover_reference's events set to the x+ of recover_trajectory's
/// impact event at the same time, at the time x+ belongs to (x_plus_time), where there is one:
/// recover_reference takes x+ at the end of the frozen run, recover_trajectory at the end of the
/// impact when the run ended before it (recover_trajectory's docstring), and the re-simulation
/// (polish()) compares each sample with the simulated state at the sample's time.
/// Also: an impact of recover_trajectory at a time where recover_reference has no event (an impact
/// absorbed into a flowing element: no frozen run, so recover_reference's samples pass through it
/// as flow) becomes an event of the reference: x- is the last sample at the event's time (the
/// element's start), x+ the trajectory's x+ at x_plus_time, inserted as a sample of the next
/// segment (with the input of the sample after it, the element's interval); when x+ falls on the
/// next sample's time, that sample (the element's end) starts the next segment as it is. Without it the re-simulation's impact had no partner in the reference, and its
/// samples around the landing were compared across the jump (measured: the plank-box short
/// landing's optimum under FesdOptions::composed_kinematics, measured 2026-12-02: 0.69 in the box's vertical velocity at t = 0.3).
template <Scene S>
void align_impact_samples(ImportedReference<S>& ref, const HybridTrajectory<S>& traj) {
  add_absorbed_impacts(ref, traj);
  for (std::size_t k = 0; k < ref.event_times.size(); ++k) {
    const double t = ref.event_times[k];
    std::size_t impact = traj.events.size();
    for (std::size_t e = 0; e < traj.events.size(); ++e)
      if (traj.events[e].impact() && std::abs(traj.events[e].t - t) <= 1e-12 * (1.0 + std::abs(t))) {
        impact = e;
        break;
      }
    if (impact == traj.events.size()) continue;
    for (std::size_t j = 0; j < ref.size(); ++j)
      if (ref.segment_of(j) == static_cast<int>(k) + 1) {
        const double t_plus = x_plus_time(traj, impact);
        const bool before_next = j + 1 >= ref.size() || t_plus < ref.t[j + 1];
        if (ref.t[j] == t && before_next) {
          ref.x[j] = traj.events[impact].x_plus;
          ref.t[j] = t_plus;
        }
        break;
      }
  }
}

/// Solves `problem` from `start` and reads the discrete solution, its events and its reference.
template <Scene S, class Problem>
TimeFreezingOcpResult<S> solve_and_read(const Problem& problem, const MpccStart& start, const FesdOptions& fesd,
                                        const MpccSolverOptions& solver) {
  TimeFreezingOcpResult<S> out;
  out.solution = solve_mpcc(problem, start, solver);
  const auto pts = problem.points(out.solution.x);
  out.points.assign(pts.begin(), pts.end());
  read_events<FesdMpcc<S>::ny, FesdMpcc<S>::nsw, S::nu, 2 * S::nq>(out.points, fesd.stages, out.element_lengths,
                                                                  out.frozen_phases, out.switch_points);
  out.reference = recover_reference<S>(out.points, fesd.stages);
  out.trajectory = recover_trajectory<S>(problem.system(), out.points, fesd.stages);
  align_impact_samples(out.reference, out.trajectory);
  return out;
}
}  // namespace detail

/// Solves the time-freezing OCP described by `ocp` (FesdMpcc's docstring lists what it may
/// provide) from (q0, v0) with FESD, by the MPCC homotopy, and recovers its reference in physical
/// time. Returns the result whether or not the homotopy converged (converged() says; the message
/// says why not). Throws InvalidArgument for bad options or states.
/// Solver settings, measured on the point mass landing and sliding to a target (N = 10, N_fe = 3):
/// the defaults (Scholtes, tol 1e-10) took 6368 Ipopt iterations; tol = 1e-8 with
/// relaxation = Penalty took 422 (two homotopy steps and the polish) and found the cheaper of
/// the two local optima (18.8 against 35.2). Known limit: at a touchdown inside an element the
/// gap's switching function is exactly 0, its multipliers vanish and cross-complementarity cannot
/// stop the active set from changing inside that element; such an impact is not a frozen run of
/// elements and recover_reference misses it (the re-simulation then differs by O(1)).
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp(const TimeFreezingSystem<S>& system, const Ocp& ocp, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, const FesdOptions& fesd,
                                                 const MpccSolverOptions& solver = {}) {
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point(start.x);
  return detail::solve_and_read<S>(problem, start, fesd, solver);
}

/// solve_time_freezing_ocp from a guess of the motion instead of the initial state at every stage
/// point: `guess(t)` -> Vec<2 nq> (q, v) at physical time t (FesdMpcc::initial_point_from_guess
/// says how the stage points, step functions and multipliers are set from it). A guess is a
/// second initialisation, e.g. a gait whose contact timing the user knows; the contact-implicit
/// setting is solve_time_freezing_ocp. Throws InvalidArgument as solve_time_freezing_ocp and for a
/// guess that is not finite.
template <Scene S, class Ocp, class Guess>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_from_guess(const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                                            const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                            const FesdOptions& fesd, const Guess& guess,
                                                            const MpccSolverOptions& solver = {}) {
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point_from_guess(start.x, guess);
  return detail::solve_and_read<S>(problem, start, fesd, solver);
}

/// A continuation on the OCP's data before the homotopy: the relaxed NLP at the first relaxation
/// parameter solver.sigma_0 is solved for each OCP of `continuation` in turn (one homotopy step
/// each, no polish), the first from FesdMpcc's initial point and each later one from the previous
/// one's primal-dual solution (the same Ocp type on the same grid: the problems have the same
/// variables, only bounds or data differ); then the whole homotopy runs on `ocp` from the last of
/// them. E.g. the hopper over three holes (scenes/hopper_holes.hpp): the holes grow from nothing
/// (hole level 1e-4) to their size while the relaxation is loose, so the iterates never face a
/// full hole across the straight path from the start to the target (without it: Ipopt's
/// Infeasible_Problem_Detected in the first step, the foot stopped at a hole's edge).
/// What can vary: the Ocp's own data (bounds of its path and terminal rows, targets, costs); the
/// grid and the control bounds are FesdOptions, one for all stages. Each stage is solved at
/// sigma_0 only (Penalty: rho_0). Its Ipopt solves are in continuation_steps, not in
/// solution.steps, and counted in solution.ipopt_iterations and seconds.
/// A continuation stage that Ipopt does not solve (its status in continuation_steps) ends the
/// continuation: the homotopy then starts from that stage's iterate (or from the last successful
/// one), and the result says so in solution.message. Throws InvalidArgument as
/// solve_time_freezing_ocp, and for an empty continuation.
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_by_continuation(const TimeFreezingSystem<S>& system,
                                                                 const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                                 const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                                 const FesdOptions& fesd,
                                                                 const MpccSolverOptions& solver = {}) {
  SALTUS_REQUIRE(!continuation.empty(), "solve_time_freezing_ocp_by_continuation: the continuation is empty");
  MpccSolverOptions one_step = solver;
  one_step.max_homotopy_steps = 1;
  one_step.polish = false;
  MpccStart start;
  std::vector<MpccHomotopyStep> steps;
  int iterations = 0;
  double seconds = 0.0;
  std::string interrupted;
  for (std::size_t c = 0; c < continuation.size(); ++c) {
    const FesdMpcc<S, Ocp> stage(system, continuation[c], q0, v0, fesd);
    if (c == 0) {
      start.x.resize(stage.variable_count());
      stage.initial_point(start.x);
    }
    const MpccSolution r = solve_mpcc(stage, start, one_step);
    for (MpccHomotopyStep st : r.steps) steps.push_back(st);
    iterations += r.ipopt_iterations;
    seconds += r.seconds;
    if (solver.progress) *solver.progress << "continuation stage " << c + 1 << " of " << continuation.size() << " done\n";
    start.x = r.x;
    start.constraint_multipliers = r.constraint_multipliers;
    start.bound_multipliers_lower = r.bound_multipliers_lower;
    start.bound_multipliers_upper = r.bound_multipliers_upper;
    if (r.steps.empty() || !r.steps.back().ipopt_succeeded) {
      interrupted = "continuation stopped at stage " + std::to_string(c + 1) + " of " + std::to_string(continuation.size()) +
                    " (" + (r.steps.empty() ? std::string("no solve") : r.steps.back().ipopt_status) + "); ";
      break;
    }
  }
  const FesdMpcc<S, Ocp> problem(system, ocp, q0, v0, fesd);
  TimeFreezingOcpResult<S> out = detail::solve_and_read<S>(problem, start, fesd, solver);
  out.continuation_steps = std::move(steps);
  out.solution.ipopt_iterations += iterations;
  out.solution.seconds += seconds;
  out.solution.message = interrupted + out.solution.message;
  return out;
}

}  // namespace saltus::timefreezing
