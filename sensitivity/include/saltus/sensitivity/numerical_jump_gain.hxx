// Definitions of numerical_jump_gain.hpp (see there for the method).
#pragma once

#include <Eigen/LU>
#include <saltus/sensitivity/detail/dense.hpp>
#include <algorithm>
#include <array>
#include <limits>
#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/simulation/integrator_dopri.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/hybrid/simulation/transition.hpp>
#include <saltus/sensitivity/numerical_jump_gain.hpp>

namespace saltus {

namespace detail {
/// The half-width of the twins' window around event e: `window`, shrunk to a quarter of the
/// distance to the neighbouring events and to the end of the trajectory. @throws InvalidArgument
template <Scene S>
double event_window(const HybridTrajectory<S>& traj, int e, double window, const char* who) {
  const Event<S>& ev = traj.events[e];
  double w = window;
  if (e > 0 && ev.t > traj.events[e - 1].t) w = std::min(w, 0.25 * (ev.t - traj.events[e - 1].t));
  if (e + 1 < static_cast<int>(traj.events.size())) w = std::min(w, 0.25 * (traj.events[e + 1].t - ev.t));
  if (traj.t_end() > ev.t) w = std::min(w, 0.25 * (traj.t_end() - ev.t));
  SALTUS_REQUIRE(w > 1e-12, who, ": no room around the event at t = ", ev.t,
                 " (neighbouring events or the end of the trajectory coincide with it)");
  return w;
}

/// x(t1) of `mode`'s smooth flow from (t0, x) under `law`, events off (the twins' Phi and Psi).
template <Scene S>
Vec<2 * S::nq> smooth_flow(const S& scene, DormandPrinceIntegrator<S>& integrator, const Mode<S::nc>& mode,
                           const InputLaw<S>& law, double t0, Vec<2 * S::nq> x, double t1) {
  ModeSystem<S> sys(scene, law);
  sys.set_mode(mode);
  integrator.integrate(sys, t0, x, t1, 0.0, nullptr, false);
  return x;
}

/// The central difference (f(h) - f(-h)) / 2h of f at 0, Richardson-extrapolated to
/// (4 D(h/2) - D(h)) / 3 when asked (O(h^4) truncation).
template <class F>
auto central_difference(F&& f, double h, bool richardson) {
  const auto d = [&](double k) { return ((f(k) - f(-k)) / (2 * k)).eval(); };
  if (!richardson) return d(h);
  return ((4 * d(0.5 * h) - d(h)) / 3).eval();
}

/// `law` with the constant dv (nu) added to its input.
template <Scene S>
InputLaw<S> shifted_input(const InputLaw<S>& law, const Vec<S::nu>& dv) {
  if constexpr (S::nu == 0) {
    return law;
  } else {
    return [law, dv](double t, const Vec<2 * S::nq>& x, const Mode<S::nc>& mode) {
      return Vec<S::nu>(law(t, x, mode) + dv);
    };
  }
}
}  // namespace detail

template <Scene S>
NumericalJumpGain<S> numerical_jump_gain(const S& scene, const HybridTrajectory<S>& traj, int e,
                                         const NumericalJumpGainOptions& options) {
  constexpr int nx = 2 * S::nq, nu = S::nu;
  using State = Vec<nx>;
  SALTUS_REQUIRE(e >= 0 && e < static_cast<int>(traj.events.size()), "event index ", e,
                " out of range [0, ", traj.events.size(), ")");
  SALTUS_REQUIRE(options.window > 0 && options.state_step > 0 && options.input_step > 0, 
                "NumericalJumpGainOptions: window and steps must be > 0");
  const Event<S>& ev = traj.events[e];
  const double ts = ev.t;
  // Several guards at one instant: when a perturbation splits them into separate events (in an
  // order that depends on the perturbation) the first-order map is conewise and no single gain
  // exists to difference; when they are coincident (the same crossing for every nearby motion:
  // jump_gain.hpp, "Coincident guards"), every perturbed run fires them together and the gain is
  // linear. The perturbed runs decide: a run that fires a subset of a transition's guards throws
  // SimultaneousActivation (split_event below).
  auto split_event = [&](std::size_t k, const std::string& what) {
    return SimultaneousActivation(detail::concat(
        "numerical jump gain: transition ", k, " of the event at t = ", ts, " is fired by ",
        ev.transitions[k].guards.size(), " guards at once, and a perturbed run ", what,
        ": perturbations split it into separate events in an order that depends on the perturbation, so the "
        "first-order map is conewise and no single gain exists to difference (numerical_conewise_piece differences "
        "one piece inside its cone)"));
  };
  const double w = detail::event_window(traj, e, options.window, "numerical jump gain");
  const double ta = ts - w, tb = ts + w;

  DormandPrinceIntegrator<S> integrator(options.simulation.integrator);
  auto smooth = [&](const Mode<S::nc>& mode, const InputLaw<S>& law, double t0, const State& x, double t1) {
    return detail::smooth_flow<S>(scene, integrator, mode, law, t0, x, t1);
  };
  const State x_a = smooth(ev.mode_before, traj.input, ts, ev.x_minus, ta);

  Simulator<S> simulator(scene, options.simulation);
  TransitionResolver<S> transitions(scene, options.simulation);
  // The same run replayed transition by transition: the integrator with event detection in each
  // mode of the reference's chain until that transition's guard fires (or at once if the guard is
  // already below zero: an immediate chained transition), then the transition's jump map
  // (apply_jump_map with the reference's impulse mode; identity for a mode change). Used when the
  // Simulator's own run fails: its chain check can cycle stick -> slip -> stick at a slip onset,
  // where the new slip's stop guard starts at zero with a rate of round-off size.
  double event_time = ts;  // of the last run through the event (its first transition)
  auto replay = [&](State x, const InputLaw<S>& law) {
    double t = ta;
    event_time = std::numeric_limits<double>::quiet_NaN();
    ModeSystem<S> sys(scene, law);
    std::array<double, 2 * S::nc + 1> gv{};
    for (std::size_t k = 0; k < ev.transitions.size(); ++k) {
      const Transition<S>& tr = ev.transitions[k];
      sys.set_mode(tr.mode_before);
      int index = -1;
      for (int j = 0; j < sys.guards().count && !tr.guards.empty(); ++j)
        if (sys.guards()[j] == tr.guards.front()) index = j;
      SALTUS_CHECK_NUMERICS(index >= 0 || tr.guards.empty(), "numerical jump gain: transition ", k,
                    " of the event at t = ", ts, " has a guard its mode does not have");
      bool cross = k == 0 && index >= 0;
      if (k > 0 && index >= 0) {
        sys.guard_values(t, x, gv);
        cross = gv[index] >= 0.0;
      }
      if (cross) {
        const auto end = integrator.integrate(sys, t, x, tb, options.simulation.simultaneity, nullptr, true);
        if (end.at_guard && !end.fired[index]) {
          // Another guard fired first: near this event the perturbed motions order the events
          // differently (guards active at nearly the same instant), not a step-size matter.
          std::string others;
          for (int j = 0; j < sys.guards().count; ++j)
            if (end.fired[j])
              others += (others.empty() ? "" : ", ") + std::string(to_string(sys.guards()[j].kind)) + " of contact '" +
                        scene.contact(sys.guards()[j].contact).name + "'";
          throw SimultaneousActivation(detail::concat(
              "numerical jump gain: a perturbed run reached ", others, " at t = ", end.t, " before the ",
              to_string(tr.guards.front().kind), " guard of the event at t = ", ts,
              ": the perturbation splits a (nearly) simultaneous event, whose first-order map is conewise"));
        }
        SALTUS_CHECK_NUMERICS(end.at_guard, "numerical jump gain: a replayed run did not reach the ",
                              to_string(tr.guards.front().kind), " guard of the event at t = ", ts,
                              " within the window [", ta, ", ", tb, "] (reduce the steps or enlarge the window)");
        for (const Guard& g : tr.guards)
          for (int j = 0; j < sys.guards().count; ++j)
            if (sys.guards()[j] == g && !end.fired[j])
              throw split_event(k, detail::concat("reached the ", to_string(tr.guards.front().kind),
                                                  " guard without the ", to_string(g.kind), " guard of contact '",
                                                  scene.contact(g.contact).name, "'"));
        t = end.t;
        if (k == 0) event_time = t;
      }
      x = transitions.replay(tr, x);
    }
    return smooth(ev.mode_after, law, t, x, tb);
  };
  int replays = 0;
  auto through = [&](const State& x0, const InputLaw<S>& law) {
    try {
      const auto run = simulator.run(x0, ev.mode_before, ta, tb, law);
      const int events = static_cast<int>(run.events.size());
      // The same structure as the reference's event: one event, the same chain, the same end mode.
      SALTUS_CHECK_NUMERICS(events == 1 && run.events.front().transitions.size() == ev.transitions.size() &&
                        run.segments.back().mode == ev.mode_after, "numerical jump gain: a perturbed run through the event at t = ", ts,
                    " ended in mode '", describe(scene, run.segments.back().mode), "' after ", events,
                    " events, not in '", describe(scene, ev.mode_after), "' after one");
      for (std::size_t k = 0; k < ev.transitions.size(); ++k)
        if (run.events.front().transitions[k].guards.size() != ev.transitions[k].guards.size())
          throw split_event(k, detail::concat("fired ", run.events.front().transitions[k].guards.size(), " of them"));
      event_time = run.events.front().t;
      return run.final_state();
    } catch (const NumericalFailure&) {
      if (!options.replay_on_failure) throw;
      ++replays;
      return replay(x0, law);
    }
  };

  // The end state and the event time of a run through the event, stacked.
  using Augmented = Vec<nx + 1>;
  auto through_timed = [&](const State& x0, const InputLaw<S>& law) {
    Augmented y;
    y.template head<nx>() = through(x0, law);
    y[nx] = event_time;
    return y;
  };

  auto difference = [&](auto&& f, double h) { return detail::central_difference(f, h, options.richardson); };

  // Admissible directions at x_a: the kernel of the Jacobian C of the mode's constraints c(x)
  // (constraints.hpp: gaps of the closed contacts, their normal velocities and the sticking
  // contacts' tangential velocities), by central differences.
  ConstraintProjection<S> constraints;
  using Values = typename ConstraintProjection<S>::Values;
  Values c_q0, c_v0, c_q, c_v;
  constraints.values(scene, ev.mode_before, x_a, c_q0, c_v0);
  const int mq = static_cast<int>(c_q0.size()), m = mq + static_cast<int>(c_v0.size());
  using Basis = typename NumericalJumpGain<S>::Basis;
  Basis T;
  Eigen::Matrix<double, Eigen::Dynamic, nx, 0, 4 * S::nc, nx> C(m, nx);
  auto constraint_row_values = [&](const State& x, int j, double sign) {
    constraints.values(scene, ev.mode_before, x, c_q, c_v);
    C.col(j).head(mq) += sign * c_q;
    C.col(j).tail(m - mq) += sign * c_v;
  };
  if (m == 0) {
    T = Mat<nx, nx>::Identity();
  } else {
    C.setZero();
    for (int j = 0; j < nx; ++j) {
      const double h = 1e-7 * std::max(1.0, std::abs(x_a[j]));
      State xp = x_a, xm = x_a;
      xp[j] += h;
      xm[j] -= h;
      constraint_row_values(xp, j, 1.0);
      constraint_row_values(xm, j, -1.0);
      C.col(j) /= 2 * h;
    }
    int rank = 0;
    T = detail::null_space(C, 1e-6, rank);
  }
  // Back onto the constraints c(x) = c(x_a) (constraints.hpp: the kinetic-metric projection;
  // perturbations are ~1e-5 along admissible directions, so the correction is ~1e-10).
  auto project = [&](State x) {
    if (m > 0) constraints.project(scene, ev.mode_before, x, &c_q0, &c_v0);
    return x;
  };

  const int r = static_cast<int>(T.cols());
  Basis P(nx, r), B(nx, r);
  Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, nx> dt_basis(1, r);
  Mat<nx, nx> Phi_plus;
  for (int j = 0; j < r; ++j) {
    const double h = options.state_step * std::max(1.0, x_a.cwiseAbs().maxCoeff());
    const auto start = [&](double k) { return project(State(x_a + k * T.col(j))); };
    const Augmented d = difference([&](double k) { return through_timed(start(k), traj.input); }, h);
    P.col(j) = d.template head<nx>();
    dt_basis[j] = d[nx];
    B.col(j) = difference([&](double k) { return smooth(ev.mode_before, traj.input, ta, start(k), ts); }, h);
  }
  for (int j = 0; j < nx; ++j) {
    const double h = options.state_step * std::max(1.0, std::abs(ev.x_plus[j]));
    Phi_plus.col(j) = difference(
        [&](double k) {
          State y = ev.x_plus;
          y[j] += k;
          return smooth(ev.mode_after, traj.input, ts, y, tb);
        },
        h);
  }
  NumericalJumpGain<S> g;
  g.window = w;
  g.basis = B;
  g.G_z_basis = detail::lu_solve(Phi_plus, P);
  g.dt_basis = dt_basis;
  g.full = r == nx;
  if (g.full) g.G_z = g.G_z_basis * detail::lu_solve(B, Mat<nx, nx>::Identity());

  if constexpr (nu > 0) {
    const Vec<nu> u_star = traj.input(ts, ev.x_minus, ev.mode_before);
    Mat<nx, nu> P_v, Psi_minus, Psi_plus;
    Eigen::Matrix<double, 1, nu> dt_v;
    for (int j = 0; j < nu; ++j) {
      const double h = options.input_step * std::max(1.0, std::abs(u_star[j]));
      auto shifted = [&](double s) { return detail::shifted_input<S>(traj.input, Vec<nu>(s * Vec<nu>::Unit(j))); };
      const Augmented d = difference([&](double k) { return through_timed(x_a, shifted(k)); }, h);
      P_v.col(j) = d.template head<nx>();
      dt_v[j] = d[nx];
      Psi_minus.col(j) = difference([&](double k) { return smooth(ev.mode_before, shifted(k), ta, x_a, ts); }, h);
      Psi_plus.col(j) = difference([&](double k) { return smooth(ev.mode_after, shifted(k), ts, ev.x_plus, tb); }, h);
    }
    // G_z Psi- = (G_z B) c with B c = Psi- (least squares; exact when Psi- is admissible).
    const Eigen::MatrixXd c = detail::minimum_norm_solve(B, Psi_minus);
    g.G_v = detail::lu_solve(Phi_plus, P_v - Psi_plus) - g.G_z_basis * c;
    // The run's event time moves by dt_dz Psi- v + dt_dv v = dt_basis c v + dt_dv v.
    g.dt_dv = dt_v - g.dt_basis * c;
  }
  g.replays = replays;
  return g;
}

template <Scene S>
NumericalConewisePiece<S> numerical_conewise_piece(const S& scene, const HybridTrajectory<S>& traj, int e,
                                                   const ConewisePiece<S>& piece,
                                                   const NumericalJumpGainOptions& options) {
  constexpr int nx = 2 * S::nq, nu = S::nu, np = nx + nu;
  using State = Vec<nx>;
  using Point = Eigen::Matrix<double, np, 1>;
  SALTUS_REQUIRE(e >= 0 && e < static_cast<int>(traj.events.size()), "event index ", e, " out of range [0, ",
                 traj.events.size(), ")");
  SALTUS_REQUIRE(options.window > 0 && options.state_step > 0 && options.input_step > 0 && options.cone_step > 0,
                 "NumericalJumpGainOptions: window and steps must be > 0");
  const Event<S>& ev = traj.events[e];
  const double ts = ev.t;
  for (int i = 0; i < S::nc; ++i)
    SALTUS_REQUIRE(!ev.mode_before[i].closed(), "numerical conewise piece: contact '", scene.contact(i).name,
                   "' is closed before the event at t = ", ts,
                   "; perturbations constrained by closed contacts are not supported here (numerical_jump_gain "
                   "handles them for single-guard events)");
  SALTUS_REQUIRE(piece.interior_direction.allFinite() && std::abs(piece.interior_direction.norm() - 1.0) < 1e-9 &&
                     piece.interior_margin > 0 && !piece.order.empty() && !piece.steps.empty(),
                 "numerical conewise piece: the piece has no order, micro-events or interior direction (not built by "
                 "ConewiseJumpGain)");
  {  // The piece's first micro-event starts from this event's x- at t*.
    const Transition<S>& first = piece.steps.front().transitions.front();
    const double gap = (first.x_before - ev.x_minus).cwiseAbs().maxCoeff();
    SALTUS_REQUIRE(piece.steps.front().t == ts && gap <= 1e-12 * std::max(1.0, ev.x_minus.cwiseAbs().maxCoeff()),
                   "numerical conewise piece: the piece was not built from event ", e, " at t = ", ts,
                   " (its first micro-event is at t = ", piece.steps.front().t, ", ", gap, " from the event's x-)");
  }
  const double w = detail::event_window(traj, e, options.window, "numerical conewise piece");
  const double ta = ts - w, tb = ts + w;

  DormandPrinceIntegrator<S> integrator(options.simulation.integrator);
  auto smooth = [&](const Mode<S::nc>& mode, const InputLaw<S>& law, double t0, const State& x, double t1) {
    return detail::smooth_flow<S>(scene, integrator, mode, law, t0, x, t1);
  };
  // The reference's input shifted by a constant dv over the window.
  auto shifted = [&](const Vec<nu>& dv) { return detail::shifted_input<S>(traj.input, dv); };
  auto difference = [&](auto&& f, double h) { return detail::central_difference(f, h, options.richardson); };
  const State x_a = smooth(ev.mode_before, traj.input, ts, ev.x_minus, ta);
  // Smooth flows on both sides: Phi-, Psi- from (ta, x_a); Phi+, Psi+ from the piece's outcome.
  Mat<nx, nx> Phi_minus, Phi_plus;
  Mat<nx, nu> Psi_minus = Mat<nx, nu>::Zero(), Psi_plus = Mat<nx, nu>::Zero();
  for (int j = 0; j < nx; ++j) {
    const double ha = options.state_step * std::max(1.0, std::abs(x_a[j]));
    Phi_minus.col(j) = difference(
        [&](double k) { return smooth(ev.mode_before, traj.input, ta, State(x_a + k * State::Unit(j)), ts); }, ha);
    const double hb = options.state_step * std::max(1.0, std::abs(piece.x_plus[j]));
    Phi_plus.col(j) = difference(
        [&](double k) { return smooth(piece.mode_after, traj.input, ts, State(piece.x_plus + k * State::Unit(j)), tb); },
        hb);
  }
  if constexpr (nu > 0) {
    const Vec<nu> u_star = traj.input(ts, ev.x_minus, ev.mode_before);
    for (int j = 0; j < nu; ++j) {
      const double h = options.input_step * std::max(1.0, std::abs(u_star[j]));
      Psi_minus.col(j) = difference(
          [&](double k) { return smooth(ev.mode_before, shifted(Vec<nu>(k * Vec<nu>::Unit(j))), ta, x_a, ts); }, h);
      Psi_plus.col(j) = difference(
          [&](double k) {
            return smooth(piece.mode_after, shifted(Vec<nu>(k * Vec<nu>::Unit(j))), ts, piece.x_plus, tb);
          },
          h);
    }
  }
  const Eigen::MatrixXd Phi_minus_inverse = detail::lu_solve(Phi_minus, Mat<nx, nx>::Identity());
  SALTUS_CHECK_NUMERICS(Phi_minus_inverse.allFinite(), "numerical conewise piece: the ante-event flow's Jacobian over ",
                        "the window is singular");

  Simulator<S> simulator(scene, options.simulation);
  NumericalConewisePiece<S> g;
  // The state at tb of the run whose deviation reaching t* is p = (z-, v) (file comment).
  auto through = [&](const Point& p) -> State {
    const State z = p.template head<nx>();
    Vec<nu> v = Vec<nu>::Zero();
    if constexpr (nu > 0) v = p.template tail<nu>();
    const State x0 = x_a + Phi_minus_inverse * (z - Psi_minus * v);
    ++g.runs;
    HybridTrajectory<S> run;
    try {
      run = simulator.run(x0, ev.mode_before, ta, tb, shifted(v));
    } catch (const InvalidArgument& err) {
      // The only input the simulator can refuse here is the start: the step exceeds the gaps.
      throw NumericalFailure(detail::concat("numerical conewise piece: the perturbation of size ", p.norm(),
                                            " starts a run inside the surface at t* - w = ", ta,
                                            " (reduce cone_step or the window): ", err.what()));
    } catch (const Error& err) {  // NumericalFailure, ContactProblemFailure, NonSpdMassMatrix
      throw NumericalFailure(detail::concat("numerical conewise piece: a perturbed run through the event at t = ", ts,
                                            " failed: ", err.what()));
    }
    // The run's events against the piece's micro-events, in order: each event's guards fill the
    // piece's current group (the simulator fires a coincident group as one event, or as several
    // when its members come apart at second order).
    std::size_t k = 0, filled = 0;
    bool follows = true;
    for (const Event<S>& re : run.events) {
      const std::vector<Guard>& fired = re.transitions.front().guards;
      follows = follows && !fired.empty() && k < piece.order.size();
      for (std::size_t i = 0; follows && i < fired.size(); ++i)
        follows = std::find(piece.order[k].begin(), piece.order[k].end(), fired[i]) != piece.order[k].end();
      if (!follows) break;
      filled += fired.size();
      if (filled >= piece.order[k].size()) {
        follows = filled == piece.order[k].size();
        ++k;
        filled = 0;
      }
    }
    follows = follows && k == piece.order.size() && filled == 0;
    const Mode<S::nc>& end = run.segments.back().mode;
    bool same = true;
    for (int i = 0; i < S::nc; ++i) same = same && end[i].mode == piece.mode_after[i].mode;
    SALTUS_CHECK_NUMERICS(follows && same, "numerical conewise piece: a perturbed run through the event at t = ", ts,
                          " fired ", run.events.size(), " events and ended in '", describe(scene, end),
                          "', not the piece's ", piece.order.size(), " micro-events ending in '",
                          describe(scene, piece.mode_after),
                          "' (the step left the cone, or the window holds other events: reduce cone_step or the window)");
    return run.final_state();
  };
  const double scale = options.cone_step * std::max(1.0, ev.x_minus.cwiseAbs().maxCoeff());
  const double r = 0.5 * std::min(1.0, piece.interior_margin);
  const Point c = piece.interior_direction;
  Eigen::Matrix<double, nx, np> M;
  for (int j = 0; j < np; ++j) {
    const Point ej = Point::Unit(j);
    const auto D = [&](double s) { return ((through(s * (c + r * ej)) - through(s * (c - r * ej))) / (2 * r * s)).eval(); };
    M.col(j) = options.richardson ? (2 * D(0.5 * scale) - D(scale)).eval() : D(scale);
  }
  g.G_z = detail::lu_solve(Phi_plus, M.template leftCols<nx>());
  if constexpr (nu > 0) g.G_v = detail::lu_solve(Phi_plus, M.template rightCols<nu>() - Psi_plus);
  g.centre = c;
  g.radius = r;
  g.step = scale;
  g.window = w;
  return g;
}

}  // namespace saltus
