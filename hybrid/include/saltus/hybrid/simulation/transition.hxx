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
  std::array<bool, nc> all{};
  all.fill(true);
  sys.set_mode(Mode<nc>{});
  start.mode = select_or_defer(sys, t0, x0, Mode<nc>{}, all, candidates, {}, start.selection_solutions,
                               start.sliding_contact);
  if (painleve_contact_ >= 0) {  // Painleve's inconsistent configuration, resolved (file comment)
    const int i = painleve_contact_;
    painleve_contact_ = -1;
    if (!initial_touchdowns.empty())
      throw ContactProblemFailure(detail::concat(
          "contact '", scene_.contact(i).name, "' starts in Painleve's inconsistent configuration while contact '",
          scene_.contact(initial_touchdowns.front().contact).name,
          "' impacts at t0: the impact without collision (SimulationOptions::painleve) is implemented for one "
          "contact, not together with an impact of another one"));
    start.impact = resolve_inconsistent(sys, t0, x0, start.mode, i);
    start.mode = start.impact->mode_after;
    start.selection_solutions = start.impact->transitions.back().selection_solutions;
    start.sliding_contact = start.impact->transitions.back().sliding_contact;
    return start;
  }
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
  struct ClearPainleve {
    int& contact;
    ~ClearPainleve() { contact = -1; }
  } clear_painleve{painleve_contact_};
  Event<S> ev;
  ev.t = t;
  // The event's physics sees the input just after the event (file comment): t is located on the
  // >= 0 side of a root, within root_tolerance * max(1, |t|) before it.
  const double t_in = t + 2 * options_.integrator.root_tolerance * std::max(1.0, std::abs(t));
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
    if (painleve_contact_ >= 0) {
      // The impact without collision a selection left to this chain (select_or_defer), or the one
      // resolve_inconsistent starts with.
      SALTUS_CHECK_NUMERICS(round < options_.max_chain, "the chain of transitions at t = ", t, " did not settle after ",
                            options_.max_chain, " transitions (last mode ", describe(scene_, mode), ")");
      const int i = painleve_contact_;
      painleve_contact_ = -1;
      Transition<S> tr;
      tr.mode_before = mode;
      tr.x_before = x;
      apply_impact_without_collision(sys, t_in, x, mode, i, tr);
      tr.mode_after = mode;
      tr.x_after = x;
      ev.transitions.push_back(std::move(tr));
      settled_friction[i] = true;  // the stick or slip chosen at rest is not undone at this instant
      pending.clear();
      continue;
    }
    if (pending.empty()) {
      sys.set_mode(mode);
      pending = guards_due(sys, t_in, x);
      std::erase_if(pending, [&](const Guard& g) {
        if (is_deferred(g)) return true;
        if (g.kind == GuardKind::Touchdown) return released[g.contact] && !(sys.guard_rate(t_in, x, g) < -v_tol);
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
    apply(sys, t_in, x, mode, pending, tr);
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
  // The release of a contact sliding with W_nn - mu s W_nt < 0: the end of the closed branch of
  // Painleve's indeterminacy, where no mode is consistent after it (file comment).
  if (options_.painleve.resolution == InconsistentContactResolution::ImpactWithoutCollision && guards.size() == 1 &&
      guards.front().kind == GuardKind::Release && painleve_slip(x, u, mode, true) == guards.front().contact) {
    apply_impact_without_collision(sys, t, x, mode, guards.front().contact, tr);
    return;
  }
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
    next = select_or_defer(sys, t, x, next, at_rest, candidates, at_rest, tr.selection_solutions, tr.sliding_contact);
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
  const double approach = -velocity_tolerance(x);  // before the impulse
  const auto& r = impact_->solve(x, in_problem, inelastic);
  tr.impact = r.impulse_mode.any();
  tr.impulse_mode = r.impulse_mode;
  // An open contact within the gap tolerance that takes an impulse touched down at this instant
  // too (a corner that reached the surface a round-off before a breakpoint, where the integrator
  // restarts, so that its crossing was not located): the transition names its guard, so that the
  // event is the simultaneous one it physically is (its gain conewise, not another contact's).
  for (int i = 0; i < nc; ++i) {
    const bool named = std::any_of(tr.guards.begin(), tr.guards.end(), [&](const Guard& g) { return g.contact == i; });
    if (mode[i].closed() || named || r.impulse_mode[i].role == ImpulseRole::None || !(kin.contacts[i].zeta_n < approach))
      continue;
    const auto after = std::find_if(tr.guards.begin(), tr.guards.end(), [&](const Guard& g) { return g.contact > i; });
    tr.guards.insert(after, Guard{i, GuardKind::Touchdown});
  }
  tr.impulse = r.impulse;
  x = r.x_plus;
  // Contacts left at zero normal velocity: choose their mode at the acceleration level, starting
  // from the impact's own post-impact mode (file comment, "Mode-dependent input laws").
  std::array<bool, nc> candidates{}, all{};
  Mode<nc> after_impact = mode;
  for (int i = 0; i < nc; ++i) {
    candidates[i] = r.post_mode[i].closed();
    if (candidates[i]) after_impact[i] = r.post_mode[i];
  }
  all.fill(true);
  sys.set_mode(after_impact);
  mode = select_or_defer(sys, t, x, after_impact, all, candidates, {}, tr.selection_solutions, tr.sliding_contact);
}

template <Scene S>
void TransitionResolver<S>::contact_delassus(const State& x, const Input& u, int i, Eigen::Matrix2d& W, double& b,
                                             double& v_n, double& v_t, double& gap) {
  Kinematics<S> kin;
  evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin);
  VecT<double, nq> free_force = -kin.h;
  if constexpr (nu > 0) free_force += kin.S_u * u;
  const auto& c = kin.contacts[i];
  const VecT<double, nq> wt = c.Wt.col(0);
  const VecT<double, nq> a_free = kin.llt.solve(free_force), Minv_wn = kin.llt.solve(c.wn), Minv_wt = kin.llt.solve(wt);
  W << c.wn.dot(Minv_wn), c.wn.dot(Minv_wt), wt.dot(Minv_wn), wt.dot(Minv_wt);
  b = c.wn.dot(a_free) + c.kappa_n;
  v_n = c.zeta_n;
  v_t = c.zeta_t[0];
  gap = c.gap;
}

template <Scene S>
int TransitionResolver<S>::inconsistent_slip(const State& x, const Input& u, const Mode<nc>& mode) {
  return painleve_slip(x, u, mode, false);
}

template <Scene S>
int TransitionResolver<S>::painleve_slip(const State& x, const Input& u, const Mode<nc>& mode, bool at_release) {
  int i = -1, closed = 0;
  for (int k = 0; k < nc; ++k)
    if (mode[k].closed()) {
      i = k;
      ++closed;
    }
  if (closed != 1 || scene_.contact(i).tangents() != 1 || mode[i].mode != ContactMode::Slip) return -1;
  Eigen::Matrix2d W;
  double b = 0.0, v_n = 0.0, v_t = 0.0, gap = 0.0;
  contact_delassus(x, u, i, W, b, v_n, v_t, gap);
  const double gap_tol = options_.impact.gap_tolerance;
  if (gap > gap_tol || gap < -100 * gap_tol) return -1;
  const double v_tol = velocity_tolerance(x);
  if (std::abs(v_n) > v_tol || std::abs(v_t) <= v_tol || v_t * mode[i].slip_direction[0] <= 0) return -1;
  const double mu = scene_.contact(i).mu, s = v_t > 0 ? 1.0 : -1.0;
  const double d = W(0, 0) - mu * s * W(0, 1), d_tol = 1e-12 * (std::abs(W(0, 0)) + mu * std::abs(W(0, 1)));
  // At a release the normal force -b/d reaches zero decreasing: b reaches zero from above when d < 0.
  return (at_release ? d < -d_tol : d <= d_tol && b < 0) ? i : -1;
}

template <Scene S>
auto TransitionResolver<S>::select_or_defer(ModeSystem<S>& sys, double t, const State& x, const Mode<nc>& base,
                                            const std::array<bool, nc>& chosen, const std::array<bool, nc>& candidates,
                                            const std::array<bool, nc>& rest, int& solutions, int& sliding)
    -> Mode<nc> {
  try {
    return select_consistent(sys, t, x, base, chosen, candidates, rest, solutions, sliding);
  } catch (const ContactProblemFailure& failure) {
    if (options_.painleve.resolution != InconsistentContactResolution::ImpactWithoutCollision) throw;
    int i = -1, closed = 0;
    std::string names;
    for (int k = 0; k < nc; ++k)
      if (candidates[k]) {
        i = k;
        ++closed;
        names += (names.empty() ? "'" : ", '") + scene_.contact(k).name + "'";
      }
    if (closed > 1)
      throw ContactProblemFailure(detail::concat(
          "no consistent contact mode at t = ", t, " with ", closed, " closed contacts (", names,
          "): the impact without collision that SimulationOptions::painleve applies to Painleve's inconsistent "
          "configuration is implemented for one closed contact, not for several (their joint tangential impulse is "
          "not); ",
          failure.what()));
    if (closed != 1 || rest[i]) throw;
    if (scene_.contact(i).tangents() == 2)
      throw ContactProblemFailure(detail::concat(
          "no consistent contact mode at t = ", t, " with contact '", scene_.contact(i).name,
          "' sliding: the impact without collision that SimulationOptions::painleve applies to Painleve's "
          "inconsistent configuration is implemented for planar friction (one tangent), and this contact has spatial "
          "friction; ",
          failure.what()));
    if (scene_.contact(i).tangents() != 1) throw;
    Kinematics<S> kin;
    evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin);
    Mode<nc> slipping = base;
    for (int k = 0; k < nc; ++k)
      if (chosen[k]) slipping[k] = ContactState::open();
    slipping[i] = ContactState::slip_planar(kin.contacts[i].zeta_t[0] > 0 ? 1 : -1);
    if (inconsistent_slip(x, sys.input_law()(t, x, slipping), slipping) != i) throw;
    painleve_contact_ = i;
    solutions = 1;
    sliding = -1;
    return slipping;
  }
}

template <Scene S>
void TransitionResolver<S>::apply_impact_without_collision(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode,
                                                           int i, Transition<S>& tr) {
  sys.set_mode(mode);
  const Input u = sys.input(t, x);
  Eigen::Matrix2d W;
  double b = 0.0, v_n = 0.0, v_t = 0.0, gap = 0.0;
  contact_delassus(x, u, i, W, b, v_n, v_t, gap);
  const ImpactWithoutCollision r = impact_without_collision(W, scene_.contact(i).mu, v_n, v_t);
  // v+ = v- + M^{-1} (w_n P_n + w_t P_t).
  Kinematics<S> kin;
  evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin);
  const VecT<double, nq> impulse = kin.contacts[i].wn * r.normal + kin.contacts[i].Wt.col(0) * r.tangent;
  x.template tail<nq>() += kin.llt.solve(impulse);
  tr.impact = true;
  tr.impact_without_collision = true;
  tr.impulse_mode = ImpactMode<nc>{};
  tr.impulse_mode[i].role = ImpulseRole::Stick;
  tr.impulse = {};
  tr.impulse[i].normal = r.normal;
  tr.impulse[i].tangent = Eigen::Vector2d(r.tangent, 0.0);
  // The contact ends at tangential rest with zero normal velocity: the acceleration-level
  // selection at rest decides stick, slip from rest or lift-off, starting from stick.
  Mode<nc> after = mode;
  after[i] = ContactState::stick();
  std::array<bool, nc> at_contact{};
  at_contact[i] = true;
  sys.set_mode(after);
  mode = select_consistent(sys, t, x, after, at_contact, at_contact, at_contact, tr.selection_solutions,
                           tr.sliding_contact);
}

template <Scene S>
Event<S> TransitionResolver<S>::resolve_inconsistent(ModeSystem<S>& sys, double t, const State& x,
                                                     const Mode<nc>& mode, int contact) {
  SALTUS_REQUIRE(options_.painleve.resolution == InconsistentContactResolution::ImpactWithoutCollision,
                 "resolve_inconsistent: SimulationOptions::painleve.resolution is ",
                 to_string(options_.painleve.resolution), ", not impact-without-collision");
  SALTUS_REQUIRE(contact >= 0 && contact < nc, "resolve_inconsistent: contact index ", contact, " out of range");
  painleve_contact_ = contact;
  return resolve(sys, t, x, mode, {});
}

template <Scene S>
auto TransitionResolver<S>::select_consistent(ModeSystem<S>& sys, double t, const State& x, const Mode<nc>& base,
                                              const std::array<bool, nc>& chosen,
                                              const std::array<bool, nc>& candidates,
                                              const std::array<bool, nc>& rest, int& solutions, int& sliding)
    -> Mode<nc> {
  sliding = -1;
  const InputLaw<S>& law = sys.input_law();
  // The modes visited, each selected under the input of the one before (file comment).
  constexpr int max_rounds = 4;
  std::array<Mode<nc>, max_rounds + 1> visited;
  visited[0] = base;
  Input u = law(t, x, base);
  for (int k = 0; k < max_rounds; ++k) {
    const Mode<nc> selected = selector_.select(x, u, candidates, rest, &visited[k]);
    solutions = selector_.uniqueness().solutions;
    Mode<nc> next = visited[k];
    for (int i = 0; i < nc; ++i)
      if (chosen[i]) next[i] = selected[i];
    if (next == visited[k]) return next;  // consistent under its own input
    const Input u_next = law(t, x, next);
    if (u_next == u) return next;  // the law does not see the difference: consistent
    for (int j = 0; j < k; ++j) {
      if (!(visited[j] == next)) continue;
      // A cycle. Sliding: two modes that differ only in one contact, closed in one of them.
      int differing = -1, count = 0;
      for (int i = 0; i < nc; ++i)
        if (!(next[i] == visited[k][i])) {
          differing = i;
          ++count;
        }
      if (j + 2 == k + 1 && count == 1 && next[differing].closed() != visited[k][differing].closed()) {
        const Mode<nc>& closed = next[differing].closed() ? next : visited[k];
        const Mode<nc>& open = next[differing].closed() ? visited[k] : next;
        sys.set_mode(closed);
        evaluate_flow(scene_, closed, x, law(t, x, closed), flow_);
        double force_scale = (flow_.kin.M * flow_.a_free).cwiseAbs().maxCoeff();
        for (int i = 0; i < nc; ++i) force_scale = std::max(force_scale, std::abs(flow_.force[i].normal));
        // The floor: clear of the release guard's zero band (guards_due: guard_tolerance times the
        // force scale), so that the sliding contact is not released by round-off.
        sys.set_sliding(differing, open, 4 * options_.guard_tolerance * force_scale);
        sliding = differing;
        return closed;
      }
      SALTUS_CHECK_NUMERICS(false, "no contact mode is consistent with the input law at t = ", t, ": under the input of ",
                            describe(scene_, visited[k]), " the selection finds ", describe(scene_, next),
                            ", which it found before under another input (the law switches with the contact mode in a "
                            "cycle that is not one contact sliding on the surface)");
    }
    visited[k + 1] = next;
    u = u_next;
  }
  SALTUS_CHECK_NUMERICS(false, "no contact mode is consistent with the input law at t = ", t, " after ", max_rounds,
                        " selections, each under the input of the mode the one before selected (last: ",
                        describe(scene_, visited[max_rounds]), ")");
  return base;  // not reached
}

template <Scene S>
auto TransitionResolver<S>::replay(const Transition<S>& tr, const State& x) -> State {
  SALTUS_REQUIRE(!tr.zeno_completion,
                 "the transition is the Zeno completion of an accumulation of impacts (a projection onto the "
                 "accumulating contacts, not the jump map of a guard crossing): it has no replay");
  if (!tr.impact) return x;
  State x_plus;
  apply_jump_map(scene_, tr.impulse_mode, x, jump_, x_plus);
  return x_plus;
}

}  // namespace saltus
