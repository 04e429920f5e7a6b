// Definitions of transition.hpp (see there for the physics).
#pragma once

#include <algorithm>
#include <cmath>
#include <saltus/hybrid/simulation/transition.hpp>

namespace saltus {

template <Scene S>
TransitionResolver<S>::TransitionResolver(const S& scene, const SimulationOptions& options)
    : scene_(scene),
      options_(options),
      impact_(std::make_unique<ImpactSolver<S>>(scene, options.impact)),
      selector_(scene, options.selection) {}

template <Scene S>
double TransitionResolver<S>::velocity_tolerance(const State& x) const {
  return options_.selection.velocity_tolerance * std::max(1.0, x.template tail<nq>().cwiseAbs().maxCoeff());
}

template <Scene S>
auto TransitionResolver<S>::start(ModeSystem<S>& sys, double t0, const State& x0) -> Start {
  // Penetration is bad input; touching contacts are closed, or impacting at t0.
  Kinematics<S> kin;
  evaluate_kinematics(scene_, VecT<double, nq>(x0.template head<nq>()), VecT<double, nq>(x0.template tail<nq>()), kin);
  std::vector<Guard> initial_touchdowns;
  std::array<bool, nc> candidates{};
  const double v_tol = velocity_tolerance(x0);
  for (int i = 0; i < nc; ++i) {
    const double gap = kin.contacts[i].gap;
    SALTUS_REQUIRE(gap >= -options_.impact.gap_tolerance, "initial state penetrates contact '",
                  scene_.contact(i).name, "': gap ", gap, " < 0");
    if (gap > options_.impact.gap_tolerance) continue;
    if (kin.contacts[i].zeta_n < -v_tol)
      initial_touchdowns.push_back({i, GuardKind::Touchdown});
    else if (kin.contacts[i].zeta_n <= v_tol)
      candidates[i] = true;
  }
  Start start;
  start.mode = selector_.select(x0, sys.input(t0, x0), candidates);
  start.selection_solutions = selector_.uniqueness().solutions;
  if (!initial_touchdowns.empty()) {
    start.impact = resolve(sys, t0, x0, start.mode, initial_touchdowns);
    start.mode = start.impact->mode_after;
  }
  return start;
}

template <Scene S>
Event<S> TransitionResolver<S>::resolve(ModeSystem<S>& sys, double t, const State& x_minus, const Mode<nc>& mode_before,
                                        std::vector<Guard> pending, const std::vector<Guard>& deferred) {
  const auto is_deferred = [&](const Guard& g) {
    return std::any_of(deferred.begin(), deferred.end(),
                       [&](const Guard& d) { return d.contact == g.contact && d.kind == g.kind; });
  };
  deferred_contacts_ = {};
  for (const Guard& g : deferred)
    if (g.kind == GuardKind::Touchdown) deferred_contacts_[g.contact] = true;
  // Cleared on every way out (the resolver is reused by the simulator).
  struct ClearDeferred {
    std::array<bool, nc>& flags;
    ~ClearDeferred() { flags = {}; }
  } clear_deferred{deferred_contacts_};
  Event<S> ev;
  ev.t = t;
  ev.x_minus = x_minus;
  ev.mode_before = mode_before;
  State x = x_minus;
  Mode<nc> mode = mode_before;
  // Contacts whose stick/slip change at this instant must not be undone at the same instant.
  // A slip that starts at a transversal slip onset (the stick force leaves the friction cone,
  // gamma' < 0) has zero tangential velocity AND zero tangential acceleration along its
  // direction d = -lambda_t/||lambda_t|| at the onset; the acceleration grows like -gamma' (t - t*)
  // after it. Its stop guard zeta_t . d therefore sits at zero with a rate that is round-off of
  // either sign, and the acceleration-level selection at that state still finds stick
  // admissible (the state is on the cone's border): re-firing it would cycle stick <-> slip.
  // Likewise a stop resolved into stick by the selection is not re-tested for slip onset.
  // Likewise a contact released at this instant (lambda_n crossed zero downwards) is not closed
  // again at this instant by its touchdown guard unless it approaches: its normal velocity is
  // that of a closed contact (zero up to the tolerance) and its normal acceleration grows from
  // zero after the release. What can still make the touchdown guard look due is the gap's drift
  // during the stance (integration error, no projection with dopri5): a gap of -1.05e-9 against
  // the 1e-9 gap tolerance made every perturbed hopper lift-off cycle open <-> slip. The
  // integrator detects a touchdown as a crossing from >= 0 to < 0, so a released contact that
  // starts slightly below zero and rises is not re-fired later either.
  std::array<bool, nc> settled_friction{}, released{};
  const double v_tol = velocity_tolerance(x_minus);
  for (int round = 0;; ++round) {
    if (pending.empty()) {
      sys.set_mode(mode);
      pending = guards_due(sys, t, x);
      std::erase_if(pending, [&](const Guard& g) {
        if (is_deferred(g)) return true;
        if (g.kind == GuardKind::Touchdown) return released[g.contact] && !(sys.guard_rate(t, x, g) < -v_tol);
        return settled_friction[g.contact] && (g.kind == GuardKind::Stop || g.kind == GuardKind::SlipOnset);
      });
      if (pending.empty()) break;
    }
    for (const Guard& g : pending) {
      if (g.kind == GuardKind::Stop || g.kind == GuardKind::SlipOnset) settled_friction[g.contact] = true;
      if (g.kind == GuardKind::Release) released[g.contact] = true;
    }
    SALTUS_CHECK_NUMERICS(round < options_.max_chain, "the chain of transitions at t = ", t,
                  " did not settle after ", options_.max_chain, " transitions (last mode ", describe(scene_, mode),
                  ")");
    Transition<S> tr;
    tr.guards = pending;
    tr.mode_before = mode;
    tr.x_before = x;
    apply(sys, t, x, mode, pending, tr);
    tr.mode_after = mode;
    tr.x_after = x;
    ev.transitions.push_back(std::move(tr));
    pending.clear();
  }
  ev.x_plus = x;
  ev.mode_after = mode;
  return ev;
}

template <Scene S>
std::vector<Guard> TransitionResolver<S>::guards_due(ModeSystem<S>& sys, double t, const State& x) {
  std::vector<Guard> due;
  typename ModeSystem<S>::GuardValues g{};
  sys.guard_values(t, x, g);
  const auto& ws = sys.flow_workspace();
  double force_scale = 0.0;
  for (int i = 0; i < nc; ++i)
    force_scale = std::max({force_scale, std::abs(ws.force[i].normal), ws.force[i].tangent.cwiseAbs().maxCoeff()});
  force_scale = std::max(force_scale, (ws.kin.M * ws.a_free).cwiseAbs().maxCoeff());
  const double v_tol = velocity_tolerance(x);
  for (int k = 0; k < sys.guards().count; ++k) {
    const Guard& guard = sys.guards()[k];
    double tol = 0.0;
    switch (guard.kind) {
      case GuardKind::Touchdown:
        tol = options_.impact.gap_tolerance;
        break;
      case GuardKind::Release:
        tol = options_.guard_tolerance * force_scale;
        break;
      case GuardKind::Stop:
        tol = v_tol;
        break;
      case GuardKind::SlipOnset:
        tol = options_.guard_tolerance * force_scale * force_scale;
        break;
    }
    if (g[k] < -tol) {
      due.push_back(guard);
    } else if (g[k] <= tol) {
      // At zero: it fires if it is decreasing (for a touchdown: only if approaching).
      const double rate = sys.guard_rate(t, x, guard);
      const double rate_tol = guard.kind == GuardKind::Touchdown ? v_tol : 0.0;
      if (rate < -rate_tol) due.push_back(guard);
    }
  }
  return due;
}

template <Scene S>
void TransitionResolver<S>::apply(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode,
                                  const std::vector<Guard>& guards, Transition<S>& tr) {
  bool touchdown = false;
  for (const Guard& g : guards) touchdown = touchdown || g.kind == GuardKind::Touchdown;
  if (touchdown) {
    apply_impact(sys, t, x, mode, guards, tr);
    return;
  }
  sys.set_mode(mode);
  const Input u = sys.input(t, x);
  evaluate_flow(scene_, mode, x, u, flow_);
  std::array<bool, nc> at_rest{};
  bool select = false;
  Mode<nc> next = mode;
  for (const Guard& g : guards) {
    const int i = g.contact;
    switch (g.kind) {
      case GuardKind::Release:
        next[i] = ContactState::open();
        break;
      case GuardKind::SlipOnset: {
        const Eigen::Vector2d lt = flow_.force[i].tangent;
        const int nt = scene_.contact(i).tangents();
        if (nt == 1)
          next[i] = ContactState::slip_planar(lt[0] > 0 ? -1 : 1);
        else
          next[i] = ContactState::slip(lt.norm() > 0 ? Eigen::Vector2d(-lt / lt.norm()) : Eigen::Vector2d(1, 0));
        break;
      }
      case GuardKind::Stop:
        at_rest[i] = true;
        select = true;
        break;
      case GuardKind::Touchdown:
        break;
    }
  }
  if (select) {
    std::array<bool, nc> candidates{};
    for (int i = 0; i < nc; ++i) candidates[i] = next[i].closed();
    const Mode<nc> chosen = selector_.select(x, u, candidates, at_rest);
    tr.selection_solutions = selector_.uniqueness().solutions;
    for (int i = 0; i < nc; ++i)
      if (at_rest[i]) next[i] = chosen[i];
  }
  mode = next;
}

template <Scene S>
void TransitionResolver<S>::apply_impact(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode,
                                         const std::vector<Guard>& guards, Transition<S>& tr) {
  Kinematics<S> kin;
  evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin);
  std::array<bool, nc> in_problem{}, inelastic{};
  for (int i = 0; i < nc; ++i)
    in_problem[i] = mode[i].closed() || (kin.contacts[i].gap <= options_.impact.gap_tolerance && !deferred_contacts_[i]);
  for (const Guard& g : guards) {
    in_problem[g.contact] = true;
    if (options_.rest_velocity > 0 && -kin.contacts[g.contact].zeta_n < options_.rest_velocity)
      inelastic[g.contact] = true;
  }
  const auto& r = impact_->solve(x, in_problem, inelastic);
  tr.impact = r.impulse_mode.any();
  tr.impulse_mode = r.impulse_mode;
  tr.impulse = r.impulse;
  x = r.x_plus;
  // Contacts left at zero normal velocity: choose their mode at the acceleration level.
  std::array<bool, nc> candidates{};
  for (int i = 0; i < nc; ++i) candidates[i] = r.post_mode[i].closed();
  sys.set_mode(mode);
  mode = selector_.select(x, sys.input(t, x), candidates);
  tr.selection_solutions = selector_.uniqueness().solutions;
}

template <Scene S>
auto TransitionResolver<S>::replay(const Transition<S>& tr, const State& x) -> State {
  if (!tr.impact) return x;
  State x_plus;
  apply_jump_map(scene_, tr.impulse_mode, x, jump_, x_plus);
  return x_plus;
}

}  // namespace saltus
