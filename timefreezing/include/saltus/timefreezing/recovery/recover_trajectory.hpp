// The physical-time HybridTrajectory of a discrete time-freezing solution (time-freezing Theorem
// 5), recovered without re-simulation: frozen runs become impact events, modes are read off the
// states and step functions.
#pragma once

#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <saltus/timefreezing/recovery/recover_reference.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {


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

}  // namespace saltus::timefreezing
