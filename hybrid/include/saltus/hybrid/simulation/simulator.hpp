// Event-driven simulation of a scene: integrate the flow of the current mode, stop at the first
// guard crossing (all four kinds, state-input guards included), resolve the event with the event
// physics of transition.hpp (impacts, releases, slip onsets, stops, and the chain of transitions
// at the same instant), continue. The backend is options.integrator.kind: Dormand-Prince
// (integrator_dopri.hpp, the default) or CVODE BDF/Adams (integrator_cvode.hpp). Guards crossing
// within `simultaneity` of each other form one simultaneous event, resolved jointly (one impact
// problem for all touchdowns).
//
// Zeno. Accumulating impacts end the run with status Zeno and the predicted accumulation time.
// They are detected on the times of all touchdown events, whichever contacts they close or
// bounce (a bouncing ball: one contact; a rocking block: its two corners in turn): when the
// intervals between consecutive touchdowns shrink geometrically over `zeno_bounces` intervals,
// with one ratio r (period 1), or with one ratio r between intervals two apart (period 2, an
// asymmetric alternation). The accumulation time is then extrapolated from the touchdown times p
// apart, s_j -> t_inf: the ratio of their intervals tends to a constant but is not one yet (a
// rocking block, balls on springs: the flight time is not proportional to the launch speed), so
// that the geometric sum of the remaining intervals, (sum of the last p intervals) r / (1 - r), is
// off by the ratio's drift. Aitken's delta-squared process, a_j = s_j - (s_j - s_{j-1})^2 /
// (s_j - 2 s_{j-1} + s_{j-2}), is exact for a geometric tail and converges faster than s_j when
// the ratio converges (Brezinski & Redivo Zaglia, Extrapolation Methods, North-Holland 1991,
// ch. 2.1); applied again to the last three a_j (the iterated process) it gives zeno_time. Its
// stated uncertainty (zeno_time_uncertainty) has two parts. The extrapolation's
// (zeno_time_extrapolation_uncertainty) is twice the change of that second order over the
// last period (from 5p + 1 touchdowns on; with 4p + 1, the change between the two orders, a
// larger estimate). Measured on balls on springs (tests/test_accumulation.cpp): errors 2.5e-7 s
// (one contact) and 2.4e-4 s (two alternating contacts) against uncertainties 1.0e-6 and 8.8e-4,
// where the geometric sum was off by 7.6e-3 and 3.8e-2 s. An uncertainty that is too large for
// the use: raise zeno_bounces (detection later, on a ratio closer to its limit). With fewer than
// 4p + 1 touchdowns, zeno_time is the geometric estimate and the uncertainty infinite. The
// integration's (zeno_time_integration_uncertainty) is the touchdown times' own error, which the
// extrapolation passes into zeno_time: 4 (relative tolerance) times the time integrated, plus the
// event location's resolution through the extrapolation's sensitivities (accumulation_time.hpp
// derives it and gives its measured margins); where it dominates, tighten the integrator's
// tolerances.
// Where the intervals shrink fast (e_n = 0.3: by 0.3^12 = 5e-7 over the default 12 bounces), they
// reach the time resolution of the event location before zeno_bounces ratios are recorded, and
// the touchdowns would merge into events at one instant ("events stall"): once the last interval
// is below 1e3 times `simultaneity`, 4 ratios within the same 5 % suffice.
// With `rest_velocity` > 0, an impact slower than it is taken as inelastic (e_n = 0): a bouncing
// contact comes to rest and the motion continues in contact. Zeno is then declared only once an
// impact slower than rest_velocity has not ended the accumulation (alternating contacts with
// e_n = 0, which the rest criterion cannot stop), so that the documented rest criterion works
// with the default zeno_bounces. Where the bounces reach the gap tolerance (the approach speed
// times the last interval below 1e3 gap_tolerance: a rocking block near rest), the touchdowns are
// located on motions of the size of the tolerance and the intervals stop shrinking regularly: 4
// ratios within 5 % suffice there too, so that raising zeno_bounces cannot drive the detection
// into that regime ("events stall" after the accumulation time).
// With `zeno_completion`, the run continues past a detected accumulation predicted before t_final:
// the accumulating contacts (those that touched down in the detection window) closed, from the
// limit state projected onto them (zeno_completion.hpp, which cites the construction), at the
// predicted time; the tail between the last touchdown and that time is recorded as one segment
// holding the state after that touchdown, and the completion as an event (its transition flagged
// zeno_completion) and in HybridTrajectory::zeno_completions, with the time's uncertainty.
//
// Sliding contacts. An input law that switches with the contact mode can make no mode consistent
// at a contact at rest on the surface (transition.hpp): the contact then slides on the surface
// under the equivalent control (ModeSystem::set_sliding); the segment records it
// (Segment::sliding_contact), statistics.sliding_events counts such events, and the trajectory's
// input applies the equivalent control there.
//
// Painleve's inconsistent configuration. A closed planar contact sliding where no nonnegative
// normal force keeps it on the surface (dynamics/impact_without_collision.hpp) has no consistent
// mode: by default the run throws (ContactProblemFailure from the mode selection of a start or
// an event; InvalidArgument from check_initial_mode where the slip is the given initial mode). With
// options.painleve.resolution = ImpactWithoutCollision the impact without collision of Genot &
// Brogliato (1999) is applied there instead, at the start (a given initial slip too) or inside an
// event's chain: a transition flagged Transition::impact_without_collision, counted in
// statistics.impacts_without_collision, after which the run continues in the mode selected with
// the contact at tangential rest. One closed contact only (transition.hpp).
//
// Invariants. Every accepted step is scanned for touchdowns that dip and come back, or start at
// round-off below the surface (guard_scan.hxx); at the end of every segment no open contact is
// below -gap_tolerance unless it started the segment lower (a contact released below the
// surface, rising): a violation is a missed event, NumericalFailure, never a `completed` run.
// More than max_chain consecutive events at one instant (zero-length segments) stop the run with
// NumericalFailure naming the guard: a cycle the chain check of one event cannot see.
// A given initial mode is checked against the state and the contact forces it implies
// (check_initial_mode).
//
// Definitions in simulator.hxx, compiled once per scene (saltus/hybrid/instantiate.hpp): a
// program that includes this header and links the scene's instantiation does not compile the
// simulator again.
#pragma once

#include <saltus/hybrid/simulation/accumulation_time.hpp>
#include <saltus/hybrid/simulation/integrator_cvode.hpp>
#include <saltus/hybrid/simulation/integrator_dopri.hpp>
#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/hybrid/simulation/transition.hpp>
#include <saltus/hybrid/simulation/zeno_completion.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <memory>
#include <optional>
#include <vector>

namespace saltus {

template <Scene S>
class Simulator {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  /// The scene must outlive the simulator. @throws InvalidArgument on a bad contact
  /// specification or non-positive tolerances.
  explicit Simulator(const S& scene, SimulationOptions options = {});
  Simulator(S&&, SimulationOptions = {}) = delete;  // would dangle
  ~Simulator();

  const SimulationOptions& options() const { return options_; }

  /// Simulates from x0 (nx = 2 nq: q then v) at t0 to t_final under `input`; the initial mode is
  /// chosen from the state (an initial impact is applied if a touching contact approaches).
  /// @throws InvalidArgument on a non-finite x0, an empty input law, t_final <= t0 or a state
  /// that penetrates a contact; NumericalFailure, ContactProblemFailure, NonSpdMassMatrix from
  /// the integration and the event physics.
  HybridTrajectory<S> run(const State& x0, double t0, double t_final, const InputLaw<S>& input);
  /// Same under a segmented law (input_law.hpp), e.g. a reference-spreading tracking controller:
  /// the law sees the index of the segment being integrated, which the plant's own events advance
  /// (an initial impact at t0 makes the first flowing segment number 1, as in the trajectory).
  /// The returned trajectory's `input` evaluates the law with the segment that contains t (the
  /// later one at an event time), so that the trajectory can still be sampled and re-simulated;
  /// its reference spreading past an event would use the next segment's law, which is not what
  /// the segmented law means there (extend a trajectory of an ordinary law instead).
  /// @throws as run above; whatever the law throws (e.g. a controller asked for a segment beyond
  /// its reference) propagates unchanged.
  HybridTrajectory<S> run(const State& x0, double t0, double t_final, const SegmentedInputLaw<S>& input);
  /// Same for a scene without inputs (nu = 0).
  HybridTrajectory<S> run(const State& x0, double t0, double t_final)
    requires(S::nu == 0)
  {
    return run(x0, t0, t_final, zero_input<S>());
  }
  /// Same, from a given initial mode.
  /// @throws InvalidArgument if mode0 is inconsistent with x0 (check_initial_mode). With
  /// options.painleve.resolution = ImpactWithoutCollision, a mode0 whose one closed contact slips
  /// into Painleve's inconsistent configuration (TransitionResolver::inconsistent_slip) is not
  /// refused: the run starts with the impact without collision at t0 (file comment).
  HybridTrajectory<S> run(const State& x0, const Mode<nc>& mode0, double t0, double t_final,
                          const InputLaw<S>& input);

  /// Checks that `mode` is a consistent mode at (t, x) under u: a closed contact touches (|gap|
  /// within the impact's gap tolerance) without normal velocity, and its normal force in that
  /// mode is >= 0 (a negative one: the mode is not admissible, e.g. a slip into a Painleve
  /// configuration whose acceleration-level problem has no solution); a sticking contact has
  /// zero tangential velocity and its force inside the friction cone; a slipping contact with a
  /// tangential velocity slides along its slip direction; an open contact is not below the
  /// surface. @throws InvalidArgument naming the first inconsistent contact and why.
  void check_initial_mode(const State& x, const Mode<nc>& mode, const Input& u) const;

 private:
  /// `segment`: the index the segmented law sees (null for an ordinary law), kept equal to the
  /// index of the segment being integrated, advanced before an event is resolved.
  HybridTrajectory<S> run_impl(const State& x0, std::optional<Mode<nc>> mode0, double t0, double t_final,
                               const InputLaw<S>& input, int* segment = nullptr);
  /// Records a touchdown event at t of the contacts `touched`, the fastest approaching at `speed`
  /// (m/s, >= 0); true when a Zeno accumulation is detected (file comment).
  bool record_touchdown(double t, const std::array<bool, nc>& touched, double speed, bool slower_than_rest,
                        HybridTrajectory<S>& traj);
  /// Continues past a detected accumulation (file comment; zeno_completion.hpp): appends the tail
  /// segment from t (the last touchdown, x after it, in `mode`) to the predicted time and the
  /// completion event, and leaves t, x and mode there. `segment` as in run_impl.
  /// @throws NumericalFailure from zeno_limit_state; as TransitionResolver::start.
  void complete_accumulation(ModeSystem<S>& sys, double& t, State& x, Mode<nc>& mode, HybridTrajectory<S>& traj,
                             int* segment);
  /// Makes traj.input the input the run applied: on a segment with a sliding contact
  /// (Segment::sliding_contact), the equivalent control (sliding_input), not the law's value in the
  /// segment's mode. The returned law refers to the scene (which outlives the simulator's runs).
  void apply_sliding_to_input(HybridTrajectory<S>& traj) const;
  /// Sets traj.zeno_time and zeno_time_uncertainty from the touchdown times at a detected
  /// accumulation of period `period` (1 or 2) and mean interval ratio `ratio` (file comment).
  void extrapolate_accumulation(int period, double ratio, HybridTrajectory<S>& traj) const;
  /// The end-of-segment invariant (file comment). @throws NumericalFailure on a missed event.
  void check_no_penetration(const State& x_begin, const State& x_end, const Mode<nc>& mode, double t) const;

  const S& scene_;
  SimulationOptions options_;
  TransitionResolver<S> transitions_;
  DormandPrinceIntegrator<S> dopri_;
  /// CVODE backend, null with Dormand-Prince. The deleter is a function pointer set where the
  /// integrator is made, so that a scene instantiated without CVODE (SALTUS_WITH_CVODE unset)
  /// never references CvodeIntegrator's code.
  std::unique_ptr<CvodeIntegrator<S>, void (*)(CvodeIntegrator<S>*)> cvode_{nullptr, nullptr};
  std::vector<double> touchdown_times_;
  std::vector<std::array<bool, nc>> touchdown_contacts_;  ///< per touchdown time: the contacts touching down
  std::vector<double> touchdown_speeds_;                  ///< per touchdown time: the fastest approach, m/s
  int zeno_window_ = 0;  ///< touchdown times the last detection used
  double touchdown_state_scale_ = 0.0;  ///< the largest |x_i| at the touchdowns (accumulation_time.hpp)
  /// s: where the touchdowns' integration error starts accumulating (the run's start, or the last
  /// accumulation the run was continued past), and that accumulation time's uncertainty.
  double accumulation_start_ = 0.0, carried_uncertainty_ = 0.0;
  ConstraintProjection<S> projection_;
  bool rest_impact_seen_ = false;
  int same_instant_events_ = 0;  ///< consecutive events at one instant (stall check)
};

}  // namespace saltus
