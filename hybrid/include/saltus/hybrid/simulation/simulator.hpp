// Event-driven simulation of a scene: integrate the flow of the current mode, stop at the first
// guard crossing (all four kinds, state-input guards included), apply the transition, follow
// chains of transitions at the same instant, continue. The backend is options.integrator.kind:
// Dormand-Prince (integrator_dopri.hpp, the default) or CVODE BDF/Adams (integrator_cvode.hpp).
//
// Transitions (thesis 2.3.3-2.3.4, appendix A.1):
//  - touchdown: the impact problem over every contact at the impact (impact.hpp), then the
//    acceleration-level choice of which of the contacts left at zero normal velocity stay
//    closed, stick or slip (mode_selection.hpp; an impact into stick may slip at once, B.3);
//  - release (lambda_n reaches 0 decreasing): the contact opens;
//  - slip onset (mu^2 lambda_n^2 - ||lambda_t||^2 reaches 0): the contact slips against its
//    friction force, d = -lambda_t/||lambda_t|| (planar: the sign);
//  - stop (the slip velocity reaches 0): the acceleration-level choice with that contact at
//    tangential rest decides between stick and slip (the other way round, for planar contacts).
// After a transition, every guard of the new mode is checked at the same instant: one that is
// already negative, or zero and decreasing, fires at once (a chain). Guards crossing within
// `simultaneity` of each other form one simultaneous event, resolved jointly (one impact problem
// for all touchdowns).
//
// Zeno. Accumulating impacts (a bouncing ball with e_n > 0) end the run with status Zeno and the
// predicted accumulation time, detected when one contact's flight times shrink geometrically
// over `zeno_bounces` consecutive touchdowns: with ratio r the remaining bounces last
// delta_last r / (1 - r). With `rest_velocity` > 0, an impact slower than it is taken as
// inelastic (e_n = 0): the contact comes to rest and the motion continues in contact.
#pragma once

#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/simulation/integrator_cvode.hxx>
#include <saltus/hybrid/simulation/integrator_dopri.hpp>
#include <saltus/hybrid/dynamics/mode_selection.hpp>
#include <saltus/hybrid/reference/reference_spreading.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

namespace saltus {

struct SimulationOptions {
  IntegratorOptions integrator;
  ImpactOptions impact;
  ModeSelectionOptions selection;
  /// s: guard crossings this close in time form one simultaneous event.
  double simultaneity = 1e-9;
  int max_events = 100000;
  /// Transitions at one instant before the chain is declared cycling.
  int max_chain = 16;
  /// Relative tolerance of "a guard is zero" when a chain is checked.
  double guard_tolerance = 1e-9;
  /// m/s (scene units): impacts slower than this are inelastic; 0 disables the rest criterion.
  double rest_velocity = 0.0;
  /// Consecutive geometrically shrinking flights of one contact that signal a Zeno accumulation.
  int zeno_bounces = 12;
  bool record_dense_output = true;
  /// Times where the input law is not smooth (e.g. a switch at t = 1): the integrator stops and
  /// restarts there, so no step straddles a kink. Sorted or not.
  std::vector<double> breakpoints;
};

template <Scene S>
class Simulator {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  explicit Simulator(const S& scene, SimulationOptions options = {})
      : scene_(scene), options_(options), impact_(make_impact_solver(scene, options)), selector_(scene, options.selection),
        dopri_(options.integrator) {
    validate_scene(scene);
    SALTUS_DEMAND(options.integrator.relative_tolerance > 0 && options.integrator.absolute_tolerance > 0,
                  InvalidArgument, "integrator tolerances must be > 0");
    // The backend: Dormand-Prince (member, always there) or CVODE (BDF/Adams), created once here.
    if (options.integrator.kind != IntegratorKind::DormandPrince)
      cvode_ = std::make_unique<CvodeIntegrator<S>>(options.integrator);
  }

  const SimulationOptions& options() const { return options_; }

  /// Simulates from x0 at t0 to t_final under `input`; the initial mode is chosen from the state
  /// (an initial impact is applied if a touching contact approaches).
  HybridTrajectory<S> run(const State& x0, double t0, double t_final, const InputLaw<S>& input) {
    return run_impl(x0, std::nullopt, t0, t_final, input);
  }
  /// Same, from a given initial mode.
  HybridTrajectory<S> run(const State& x0, const Mode<nc>& mode0, double t0, double t_final, const InputLaw<S>& input) {
    return run_impl(x0, mode0, t0, t_final, input);
  }

 private:
  static ImpactSolver<S>* make_impact_solver(const S& scene, const SimulationOptions& o) {
    return new ImpactSolver<S>(scene, o.impact);
  }

  HybridTrajectory<S> run_impl(const State& x0, std::optional<Mode<nc>> mode0, double t0, double t_final,
                               const InputLaw<S>& input) {
    const auto wall_start = std::chrono::steady_clock::now();
    require_finite(x0, "initial state x0");
    SALTUS_DEMAND(std::isfinite(t0) && std::isfinite(t_final) && t_final > t0, InvalidArgument,
                  "simulation interval must be finite with t_final > t0, got [", t0, ", ", t_final, "]");
    SALTUS_DEMAND(static_cast<bool>(input), InvalidArgument, "the input law is empty");
    HybridTrajectory<S> traj;
    traj.input = input;
    ModeSystem<S> sys(scene_, input);
    touchdown_times_.fill({});

    double t = t0;
    State x = x0;
    Mode<nc> mode;
    if (mode0) {
      mode = *mode0;
    } else {
      // Penetration is bad input; touching contacts are closed, or impacting at t0.
      Kinematics<S> kin;
      evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin);
      std::vector<Guard> initial_touchdowns;
      std::array<bool, nc> candidates{};
      const double v_tol = velocity_tolerance(x);
      for (int i = 0; i < nc; ++i) {
        const double gap = kin.contacts[i].gap;
        SALTUS_DEMAND(gap >= -options_.impact.gap_tolerance, InvalidArgument, "initial state penetrates contact '",
                      scene_.contact(i).name, "': gap ", gap, " < 0");
        if (gap > options_.impact.gap_tolerance) continue;
        if (kin.contacts[i].zeta_n < -v_tol)
          initial_touchdowns.push_back({i, GuardKind::Touchdown});
        else if (kin.contacts[i].zeta_n <= v_tol)
          candidates[i] = true;
      }
      mode = selector_.select(x, sys.input(t, x), candidates);
      if (!initial_touchdowns.empty()) {
        Event<S> ev = resolve_event(sys, t, x, mode, initial_touchdowns);
        x = ev.x_plus;
        mode = ev.mode_after;
        traj.events.push_back(std::move(ev));
        traj.segments.push_back(Segment<S>{traj.events.back().mode_before, t, t, {}});
      }
    }

    SimulationStatistics& stats = traj.statistics;
    while (true) {
      sys.set_mode(mode);
      Segment<S> seg;
      seg.mode = mode;
      seg.t_begin = t;
      const long rhs_before = sys.rhs_evaluations();
      SegmentEndOf<S> end;
      while (true) {
        // Integrate up to the next breakpoint of the input, or t_final.
        double t_stop = t_final;
        for (double b : options_.breakpoints)
          if (b > t * (1 + 1e-15) + 1e-300 && b < t_stop) t_stop = b;
        DenseOutput<nx>* dense = options_.record_dense_output ? &seg.x : nullptr;
        end = cvode_ ? cvode_->integrate(sys, t, x, t_stop, options_.simultaneity, dense)
                     : dopri_.integrate(sys, t, x, t_stop, options_.simultaneity, dense);
        stats.steps += end.steps;
        stats.rejected_steps += end.rejected_steps;
        t = end.t;
        if (end.at_guard || t_stop == t_final) break;
      }
      stats.rhs_evaluations += sys.rhs_evaluations() - rhs_before;
      seg.t_end = end.t;
      traj.segments.push_back(std::move(seg));
      if (!end.at_guard) break;

      std::vector<Guard> fired;
      for (int k = 0; k < sys.guards().count; ++k)
        if (end.fired[k]) fired.push_back(sys.guards()[k]);
      Event<S> ev = resolve_event(sys, t, x, mode, fired);
      x = ev.x_plus;
      mode = ev.mode_after;
      // Zeno bookkeeping on touchdowns that bounced (the contact is open again afterwards).
      bool zeno = false;
      for (const Guard& g : ev.guards())
        if (g.kind == GuardKind::Touchdown && !mode[g.contact].closed()) zeno = zeno || record_touchdown(g.contact, t, traj);
      traj.events.push_back(std::move(ev));
      if (zeno) {
        traj.status = SimulationStatus::Zeno;
        break;
      }
      if (static_cast<int>(traj.events.size()) >= options_.max_events) {
        traj.status = SimulationStatus::MaxEvents;
        break;
      }
    }
    traj.set_final_state(x);
    stats.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    return traj;
  }

  double velocity_tolerance(const State& x) const {
    return options_.selection.velocity_tolerance * std::max(1.0, x.template tail<nq>().cwiseAbs().maxCoeff());
  }

  /// The transitions at time t from x (the state just before), starting with the fired guards.
  Event<S> resolve_event(ModeSystem<S>& sys, double t, const State& x_minus, const Mode<nc>& mode_before,
                         std::vector<Guard> pending) {
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
          if (g.kind == GuardKind::Touchdown) return released[g.contact] && !(sys.guard_rate(t, x, g) < -v_tol);
          return settled_friction[g.contact] && (g.kind == GuardKind::Stop || g.kind == GuardKind::SlipOnset);
        });
        if (pending.empty()) break;
      }
      for (const Guard& g : pending) {
        if (g.kind == GuardKind::Stop || g.kind == GuardKind::SlipOnset) settled_friction[g.contact] = true;
        if (g.kind == GuardKind::Release) released[g.contact] = true;
      }
      SALTUS_DEMAND(round < options_.max_chain, NumericalFailure, "the chain of transitions at t = ", t,
                    " did not settle after ", options_.max_chain, " transitions (last mode ",
                    describe(scene_, mode), ")");
      Transition<S> tr;
      tr.guards = pending;
      tr.mode_before = mode;
      tr.x_before = x;
      apply_transition(sys, t, x, mode, pending, tr);
      tr.mode_after = mode;
      tr.x_after = x;
      ev.transitions.push_back(std::move(tr));
      pending.clear();
    }
    ev.x_plus = x;
    ev.mode_after = mode;
    return ev;
  }

  /// Guards of the current mode that must fire now: below -tolerance, or within it and decreasing.
  std::vector<Guard> guards_due(ModeSystem<S>& sys, double t, const State& x) {
    std::vector<Guard> due;
    std::array<double, ng> g{};
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
        case GuardKind::Touchdown: tol = options_.impact.gap_tolerance; break;
        case GuardKind::Release: tol = options_.guard_tolerance * force_scale; break;
        case GuardKind::Stop: tol = v_tol; break;
        case GuardKind::SlipOnset: tol = options_.guard_tolerance * force_scale * force_scale; break;
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

  void apply_transition(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode, const std::vector<Guard>& guards,
                        Transition<S>& tr) {
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
        case GuardKind::Release: next[i] = ContactState::open(); break;
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
        case GuardKind::Touchdown: break;
      }
    }
    if (select) {
      std::array<bool, nc> candidates{};
      for (int i = 0; i < nc; ++i) candidates[i] = next[i].closed();
      const Mode<nc> chosen = selector_.select(x, u, candidates, at_rest);
      for (int i = 0; i < nc; ++i)
        if (at_rest[i]) next[i] = chosen[i];
    }
    mode = next;
  }

  void apply_impact(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode, const std::vector<Guard>& guards,
                    Transition<S>& tr) {
    Kinematics<S> kin;
    evaluate_kinematics(scene_, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin);
    std::array<bool, nc> in_problem{}, inelastic{};
    for (int i = 0; i < nc; ++i) in_problem[i] = mode[i].closed() || kin.contacts[i].gap <= options_.impact.gap_tolerance;
    for (const Guard& g : guards) {
      in_problem[g.contact] = true;
      if (options_.rest_velocity > 0 && -kin.contacts[g.contact].zeta_n < options_.rest_velocity) inelastic[g.contact] = true;
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
  }

  /// Records a touchdown of contact i that bounced; true when a Zeno accumulation is detected.
  bool record_touchdown(int i, double t, HybridTrajectory<S>& traj) {
    auto& times = touchdown_times_[i];
    times.push_back(t);
    const int n = options_.zeno_bounces;
    if (static_cast<int>(times.size()) < n + 2) return false;
    // Flight times between the last n + 2 touchdowns, and their ratios.
    const std::size_t m = times.size();
    double r_min = 1.0, r_max = 0.0, last_flight = 0.0;
    for (int k = 0; k < n; ++k) {
      const double f1 = times[m - 1 - k] - times[m - 2 - k];
      const double f0 = times[m - 2 - k] - times[m - 3 - k];
      if (!(f0 > 0 && f1 > 0)) return false;
      const double r = f1 / f0;
      r_min = std::min(r_min, r);
      r_max = std::max(r_max, r);
      if (k == 0) last_flight = f1;
    }
    if (!(r_max < 1.0 && r_max - r_min < 0.05)) return false;
    const double ratio = 0.5 * (r_min + r_max);
    traj.zeno_time = t + last_flight * ratio / (1.0 - ratio);
    return true;
  }

  const S& scene_;
  SimulationOptions options_;
  std::unique_ptr<ImpactSolver<S>> impact_;
  ModeSelector<S> selector_;
  DormandPrinceIntegrator<S> dopri_;
  std::unique_ptr<CvodeIntegrator<S>> cvode_;  ///< null with Dormand-Prince
  FlowWorkspace<S> flow_;
  std::array<std::vector<double>, nc> touchdown_times_;
};

/// The result of polishing an imported reference.
template <Scene S>
struct PolishResult {
  HybridTrajectory<S> trajectory;  ///< the re-simulation under the imported input
  /// max over the samples of ||x_imported - x_simulated||_inf. Each sample is compared with the
  /// simulated segment that has seen the same number of events, extended past its ends by
  /// reference spreading (reference_spreading.hpp) over the largest event-time difference, so a
  /// sample just before an imported event is not compared with a post-event state because the
  /// simulated event came 1e-11 s earlier; samples outside every such segment are compared with
  /// the simulated state at their time.
  double state_distance = 0.0;
  /// max |t_imported - t_simulated| over the events, paired in order; infinite if the counts differ.
  double event_time_distance = 0.0;
  std::size_t imported_events = 0, simulated_events = 0;
};

/// Re-simulates an imported reference with the event-driven simulator from its first sample
/// under its own input, u(t) interpolated linearly between the samples
/// (ImportedReference::input), and measures how far the two are apart (the validation protocol's
/// step 5). With `breakpoints_at_samples` every sample time is an input breakpoint, so that no
/// integration step straddles a kink of the interpolated input. Throws InvalidArgument on a bad
/// reference (validate()), and whatever the simulation throws.
template <Scene S>
PolishResult<S> polish(const S& scene, const ImportedReference<S>& reference, SimulationOptions options = {},
                       bool breakpoints_at_samples = true) {
  reference.validate();
  const auto samples = std::make_shared<const ImportedReference<S>>(reference);
  const double t0 = reference.t.front(), t1 = reference.t.back();
  if (breakpoints_at_samples)
    for (double t : reference.t)
      if (t > t0 && t < t1 && (options.breakpoints.empty() || options.breakpoints.back() != t))
        options.breakpoints.push_back(t);
  const InputLaw<S> input = [samples](double t, const VecT<double, 2 * S::nq>&, const Mode<S::nc>&) {
    return samples->input(t);
  };
  Simulator<S> simulator(scene, options);
  PolishResult<S> result{simulator.run(reference.x.front(), t0, t1, input)};
  const auto& traj = result.trajectory;
  result.imported_events = reference.event_times.size();
  result.simulated_events = traj.events.size();
  if (result.imported_events != result.simulated_events) {
    result.event_time_distance = std::numeric_limits<double>::infinity();
  } else {
    for (std::size_t e = 0; e < traj.events.size(); ++e)
      result.event_time_distance =
          std::max(result.event_time_distance, std::abs(reference.event_times[e] - traj.events[e].t));
  }
  ExtensionOptions spread;
  spread.before = spread.after =
      std::isfinite(result.event_time_distance) ? 2 * result.event_time_distance + 1e-12 * (1 + std::abs(t1)) : 0.0;
  spread.integrator = options.integrator;
  const ExtendedReference<S> extended(scene, traj, spread);
  for (std::size_t k = 0; k < reference.size(); ++k) {
    const double t = reference.t[k];
    const int s = reference.segment_of(k);
    VecT<double, 2 * S::nq> x_sim;
    if (s < traj.segment_count() && t >= extended.t_begin(s) && t <= extended.t_end(s))
      x_sim = extended.state(s, t);
    else
      x_sim = traj.state_at(t);
    result.state_distance = std::max(result.state_distance, (reference.x[k] - x_sim).cwiseAbs().maxCoeff());
  }
  return result;
}

}  // namespace saltus
