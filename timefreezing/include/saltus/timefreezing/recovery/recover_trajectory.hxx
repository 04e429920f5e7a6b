// The definition of recover_trajectory (recover_trajectory.hpp, where its rules are stated): a
// reader of the FESD points (modes, frozen runs, pieces) and a writer of the trajectory (segments
// and events), walking the elements once.
#pragma once

#include <saltus/timefreezing/recovery/recover_reference.hxx>
#include <saltus/timefreezing/recovery/recover_trajectory.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

namespace detail {

/// One recovery: the points, their reading (read-only helpers) and the trajectory being written.
template <Scene S, int ny, int nsw, int nu>
class TrajectoryRecovery {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nc = S::nc;
  using Point = FesdPoint<ny, nsw, nu>;
  using ModeT = Mode<nc>;
  using State = VecT<double, nx>;
  static_assert(ny == nx + 2 + nc && nsw == 3 * nc, "recover_trajectory: points of another scene");

  TrajectoryRecovery(const TimeFreezingSystem<S>& system, const std::vector<Point>& points, int stages,
                     const TrajectoryRecoveryOptions& options)
      : system_(system), points_(points), stages_(stages), options_(options),
        elements_(static_cast<int>((points.size() - 1) / static_cast<std::size_t>(stages))) {}

  /// Walks the elements: a run of frozen elements is an impact, a collapsed element is skipped, a
  /// flowing element extends the segment or starts the next one after a mode change.
  HybridTrajectory<S> run(const ImportedReference<S>& samples) {
    traj_.input = [samples](double t, const State&, const ModeT&) { return samples.input(t); };
    for (std::size_t k = 0; k + 1 < samples.t.size(); ++k)  // a repeated time: the control interval's jump
      if (samples.t[k] == samples.t[k + 1] && (traj_.input_breakpoints.empty() || traj_.input_breakpoints.back() != samples.t[k]))
        traj_.input_breakpoints.push_back(samples.t[k]);
    seg_.t_begin = seg_.t_end = clock(points_[0]);
    current_ = mode_at(points_[0]);
    for (int e = 0; e < elements_;) {
      if (frozen(e)) e = frozen_run(e);
      else if (degenerate(e)) ++e;  // collapsed to a point by FESD: no mode, no piece
      else e = flowing_element(e);
    }
    if (!seg_has_mode_) seg_.mode = current_;
    seg_.t_end = std::max(seg_.t_begin, clock(points_.back()));
    traj_.segments.push_back(seg_);
    traj_.set_final_state(state(points_.back()));
    traj_.status = SimulationStatus::Completed;
    return std::move(traj_);
  }

 private:
  // ---- reading the points ----
  const Point& start_of(int e) const { return points_[static_cast<std::size_t>(e == 0 ? 0 : e * stages_)]; }
  const Point& stage_of(int e, int r) const { return points_[static_cast<std::size_t>(1 + e * stages_ + r)]; }
  const Point& end_of(int e) const { return stage_of(e, stages_ - 1); }
  static State state(const Point& p) { return State(p.y.template head<nx>()); }
  static double clock(const Point& p) { return p.y[nx]; }
  Vec<nsw> switching(const Point& p) const {
    return system_.template switching_functions<double>(Vec<nq>(p.y.template head<nq>()),
                                                        Vec<nq>(p.y.template segment<nq>(nq)));
  }
  bool frictional(int i) const { return system_.has_friction(i) && system_.scene().contact(i).mu > 0.0; }
  bool approaching(const Vec<nsw>& c, int i) const {
    return c[3 * i] <= options_.gap_tolerance && c[3 * i + 1] < -options_.velocity_tolerance;
  }
  /// One contact's state at one point: 0 open, 1 stick, 2 slip+, 3 slip-, 4 closed frictionless.
  int contact_class(const Vec<nsw>& c, int i) const {
    if (!(c[3 * i] <= options_.gap_tolerance && std::abs(c[3 * i + 1]) <= options_.velocity_tolerance))
      return 0;  // open, or approaching
    if (!frictional(i)) return 4;
    const double vt = c[3 * i + 2];
    return std::abs(vt) <= options_.tangential_velocity_tolerance ? 1 : (vt > 0.0 ? 2 : 3);
  }
  static ContactState to_state(int cls) {
    switch (cls) {
      case 1: return ContactState::stick();
      case 2: return ContactState::slip_planar(1);
      case 3: return ContactState::slip_planar(-1);
      case 4: return ContactState::slip(Eigen::Vector2d::Zero());
      default: return ContactState::open();
    }
  }
  /// The element's mode from its last interior stage point (the end point is the next element's
  /// start and sits on the switching surface when the switch is there; n_s = 1 has only the end
  /// point): a switch inside the element is read at its end. A contact closed by its state but
  /// without closing weight there carries no force and is open (closing_weight_tolerance).
  ModeT mode_of_element(int e) const {
    ModeT m;
    const Point& p = stage_of(e, stages_ >= 2 ? stages_ - 2 : 0);
    const Vec<nsw> c = switching(p);
    for (int i = 0; i < nc; ++i) {
      const double weight = TimeFreezingSystem<S>::template closing_weight<double>(p.alpha, i);
      m[i] = to_state(weight < options_.closing_weight_tolerance ? 0 : contact_class(c, i));
    }
    return m;
  }
  ModeT mode_at(const Point& p) const {
    ModeT m;
    const Vec<nsw> c = switching(p);
    for (int i = 0; i < nc; ++i) m[i] = to_state(contact_class(c, i));
    return m;
  }
  bool degenerate(int e) const { return element_degenerate(points_, stages_, e); }
  bool frozen(int e) const { return !degenerate(e) && element_frozen(points_, stages_, e, options_.frozen_tolerance); }
  /// The earliest stage r <= last of element e such that `holds` (of the switching functions) is
  /// true at every stage r .. last; -1 when it is false at `last`.
  template <class Holds>
  int start_of_trailing_run(int e, int last, const Holds& holds) const {
    int first = -1;
    for (int r = last; r >= 0 && holds(switching(stage_of(e, r))); --r) first = r;
    return first;
  }
  /// How contact i took an impulse, as the impact solver labels it: stick for a frictionless
  /// contact or a tangential rest after the impact, else slip along J_t v+ (c_plus: the switching
  /// functions at x+).
  ImpulseMode impulse_role(int i, const Vec<nsw>& c_plus) const {
    const double vt = c_plus[3 * i + 2];
    if (!frictional(i) || std::abs(vt) <= options_.tangential_velocity_tolerance)
      return ImpulseMode{ImpulseRole::Stick, Eigen::Vector2d::Zero()};
    return ImpulseMode{ImpulseRole::Slip, Eigen::Vector2d(vt > 0.0 ? 1.0 : -1.0, 0.0)};
  }
  /// The guards of a mode change without impact, per contact that changed.
  static std::vector<Guard> changes(const ModeT& before, const ModeT& after) {
    std::vector<Guard> guards;
    for (int i = 0; i < nc; ++i) {
      if (before[i] == after[i]) continue;
      if (!before[i].closed()) guards.push_back({i, GuardKind::Touchdown});
      else if (!after[i].closed()) guards.push_back({i, GuardKind::Release});
      else if (after[i].mode == ContactMode::Stick) guards.push_back({i, GuardKind::Stop});
      else guards.push_back({i, GuardKind::SlipOnset});
    }
    return guards;
  }
  PolynomialPiece<nx> piece_of(int e, int first = -1) const;

  // ---- writing the trajectory ----
  void close_segment(double t_end) {
    seg_.t_end = t_end;
    traj_.segments.push_back(seg_);
    seg_ = Segment<S>{};
    seg_.t_begin = seg_.t_end = t_end;
    seg_has_mode_ = false;
  }
  /// Closes the segment at t, adds the event and opens the next segment in mode `after`.
  void add_event(double t, const State& xm, const State& xp, const ModeT& after, std::vector<Guard> guards,
                 bool impact, const ImpactMode<nc>& impulse = {}) {
    if (!seg_has_mode_) seg_.mode = current_;
    close_segment(t);
    Event<S> ev;
    ev.t = t;
    ev.x_minus = xm;
    ev.x_plus = xp;
    ev.mode_before = current_;
    ev.mode_after = after;
    Transition<S> tr;
    tr.guards = std::move(guards);
    tr.mode_before = current_;
    tr.mode_after = after;
    tr.x_before = xm;
    tr.x_after = xp;
    tr.impact = impact;
    if (impact) tr.impulse_mode = impulse;
    ev.transitions.push_back(std::move(tr));
    traj_.events.push_back(std::move(ev));
    current_ = after;
    seg_.mode = after;
    seg_has_mode_ = true;
  }
  /// Where the clock advanced past an impact's time t before its x+ (at `plus`): x+ held constant
  /// over [t, clock(plus)] (recover_trajectory's docstring).
  void hold_over_advance(double t, const Point& plus) {
    if (!(clock(plus) > t)) return;
    PolynomialPiece<nx> hold;
    hold.t0 = hold.t_ref = t;
    hold.t1 = clock(plus);
    hold.h = hold.t1 - t;
    hold.degree = 0;
    hold.c.col(0) = state(plus);
    seg_.x.append(hold);
  }
  int unfinished_impact_tail(int f) const;
  ImpactMode<nc> run_impulse(int e, int f, const Point& plus) const;
  int frozen_run(int e);
  int flowing_element(int e);
  int absorbed_impact(int e, const ModeT& m, const std::vector<int>& struck);

  const TimeFreezingSystem<S>& system_;
  const std::vector<Point>& points_;
  const int stages_;
  const TrajectoryRecoveryOptions& options_;
  const int elements_;
  HybridTrajectory<S> traj_;
  Segment<S> seg_;
  bool seg_has_mode_ = false;
  ModeT current_;
};

/// The piece of element e in physical time, through its points from `first` on (-1: the element's
/// start point, r >= 0: stage r) to its end: the interpolating polynomial in theta = (t - t0) / h,
/// or the straight line between its end nodes where the nodes' clocks are not increasing.
template <Scene S, int ny, int nsw, int nu>
auto TrajectoryRecovery<S, ny, nsw, nu>::piece_of(int e, int first) const -> PolynomialPiece<nx> {
  PolynomialPiece<nx> p;
  const int n = stages_ - first;  // the number of nodes, 2 .. n_s + 1 (1 when first is the end)
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
  // The Vandermonde system, n <= 4 (not a hot path: once per element of a recovered solution).
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
}

/// An impact that the frozen run ending at element f did not finish (a contact still approaching
/// at the run's end ends inside the next, flowing element): the stage of element f + 1 from which
/// on no such contact approaches any more, which holds x+; -1 when the run finished its impact.
template <Scene S, int ny, int nsw, int nu>
int TrajectoryRecovery<S, ny, nsw, nu>::unfinished_impact_tail(int f) const {
  if (f + 1 >= elements_) return -1;
  const Vec<nsw> c_end = switching(end_of(f));
  std::vector<int> still;
  for (int i = 0; i < nc; ++i)
    if (approaching(c_end, i)) still.push_back(i);
  if (still.empty()) return -1;
  return start_of_trailing_run(f + 1, stages_ - 1, [&](const Vec<nsw>& cr) {
    bool done = true;
    for (int i : still) done = done && cr[3 * i + 1] >= -options_.velocity_tolerance;
    return done;
  });
}

/// Who took an impulse in the frozen run e .. f: a contact whose closing weight
/// (1 - alpha_gap)(1 - alpha_vn) reached 1/2 at a stage point of the run; how: impulse_role at x+.
template <Scene S, int ny, int nsw, int nu>
auto TrajectoryRecovery<S, ny, nsw, nu>::run_impulse(int e, int f, const Point& plus) const -> ImpactMode<nc> {
  ImpactMode<nc> impulse;
  const Vec<nsw> c_plus = switching(plus);
  for (int i = 0; i < nc; ++i) {
    double closing = 0.0;
    for (int g = e; g <= f; ++g)
      for (int r = 0; r < stages_; ++r)
        closing = std::max(closing, TimeFreezingSystem<S>::template closing_weight<double>(stage_of(g, r).alpha, i));
    if (closing >= 0.5) impulse[i] = impulse_role(i, c_plus);
  }
  return impulse;
}

/// The run of frozen elements from e: one impact event at the run's start (x- its start state, x+
/// its end state or the unfinished impact's tail), guards Touchdown for the open contacts that
/// approach at x-. Returns the next element to read.
template <Scene S, int ny, int nsw, int nu>
int TrajectoryRecovery<S, ny, nsw, nu>::frozen_run(int e) {
  int f = e;
  while (f + 1 < elements_ && frozen(f + 1)) ++f;
  const Point& minus = start_of(e);
  const double t = clock(minus);
  const int tail = unfinished_impact_tail(f);
  const Point& plus = tail >= 0 ? stage_of(f + 1, tail) : end_of(f);
  int next = f + 1;  // the next element with a length (collapsed ones say nothing of a mode)
  while (next < elements_ && degenerate(next)) ++next;
  const ModeT after = next < elements_ ? mode_of_element(next) : mode_at(plus);
  const Vec<nsw> c = switching(minus);
  std::vector<Guard> guards;
  for (int i = 0; i < nc; ++i)
    if (!current_[i].closed() && approaching(c, i)) guards.push_back({i, GuardKind::Touchdown});
  add_event(t, state(minus), state(plus), after, std::move(guards), true, run_impulse(e, f, plus));
  hold_over_advance(t, plus);
  e = f + 1;
  if (tail >= 0) {  // the impact's tail: element f + 1 from x+ on
    if (tail < stages_ - 1) seg_.x.append(piece_of(e, tail));
    ++e;
  }
  return e;
}

/// A flowing element: extends the segment in the same mode; a mode change is an event at the
/// element's start (an absorbed impact when contacts that were open close while approaching).
/// Returns the next element to read.
template <Scene S, int ny, int nsw, int nu>
int TrajectoryRecovery<S, ny, nsw, nu>::flowing_element(int e) {
  const ModeT m = mode_of_element(e);
  if (!seg_has_mode_) {  // the first element (after an impact the next element's mode is set)
    seg_.mode = m;
    seg_has_mode_ = true;
  } else if (!(m == seg_.mode)) {
    const Vec<nsw> c = switching(start_of(e));
    std::vector<int> struck;
    for (int i = 0; i < nc; ++i)
      if (!current_[i].closed() && m[i].closed() && c[3 * i + 1] < -options_.velocity_tolerance) struck.push_back(i);
    if (!struck.empty()) return absorbed_impact(e, m, struck);
    add_event(clock(start_of(e)), state(start_of(e)), state(start_of(e)), m, changes(current_, m), false);
  }
  current_ = m;
  seg_.x.append(piece_of(e));
  return e + 1;
}

/// An impact absorbed into flowing element e (recover_trajectory's docstring): read as an impact
/// at the element's start with x+ at its first stage point from which on every struck contact is
/// closed, held over the clock advance to it. Returns the next element to read.
template <Scene S, int ny, int nsw, int nu>
int TrajectoryRecovery<S, ny, nsw, nu>::absorbed_impact(int e, const ModeT& m, const std::vector<int>& struck) {
  const double t = clock(start_of(e));
  // From the stage that decided the element's mode (closed for them) back to the earliest stage of
  // a closed run.
  const int deciding = stages_ >= 2 ? stages_ - 2 : 0;
  int first_closed = start_of_trailing_run(e, deciding, [&](const Vec<nsw>& cr) {
    bool closed = true;
    for (int i : struck) closed = closed && contact_class(cr, i) != 0;
    return closed;
  });
  if (first_closed < 0) first_closed = deciding;
  const Point& plus = stage_of(e, first_closed);
  ImpactMode<nc> impulse;
  const Vec<nsw> c_plus = switching(plus);
  for (int i : struck) impulse[i] = impulse_role(i, c_plus);
  add_event(t, state(start_of(e)), state(plus), m, changes(current_, m), true, impulse);
  hold_over_advance(t, plus);
  if (first_closed < stages_ - 1) seg_.x.append(piece_of(e, first_closed));
  return e + 1;
}

}  // namespace detail

template <Scene S, int ny, int nsw, int nu>
HybridTrajectory<S> recover_trajectory(const TimeFreezingSystem<S>& system,
                                       const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       const TrajectoryRecoveryOptions& options) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  SALTUS_REQUIRE(positive(options.gap_tolerance) && positive(options.velocity_tolerance) &&
                     positive(options.tangential_velocity_tolerance) && positive(options.frozen_tolerance),
                 "recover_trajectory: the tolerances must be finite and > 0, got gap ", options.gap_tolerance,
                 ", velocity ", options.velocity_tolerance, ", tangential velocity ",
                 options.tangential_velocity_tolerance, ", frozen ", options.frozen_tolerance);
  SALTUS_REQUIRE(positive(options.closing_weight_tolerance) && options.closing_weight_tolerance < 1.0,
                 "recover_trajectory: closing_weight_tolerance must be in (0, 1), got ", options.closing_weight_tolerance);
  const ImportedReference<S> samples = detail::control_samples<S>(points, stages);
  return detail::TrajectoryRecovery<S, ny, nsw, nu>(system, points, stages, options).run(samples);
}

}  // namespace saltus::timefreezing
