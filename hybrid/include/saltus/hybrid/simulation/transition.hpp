// The event physics: what happens when guards fire. One component, used by the simulator, the
// numerical twin of the jump gains and the conewise gains of simultaneous events, so that every
// analysis composes exactly the transitions the simulator takes (thesis 2.3.3-2.3.4, appendix A.1):
//  - touchdown: the impact problem over every contact at the impact (dynamics/impact.hpp), then
//    the acceleration-level choice of which of the contacts left at zero normal velocity stay
//    closed, stick or slip (dynamics/mode_selection.hpp; an impact into stick may slip at once,
//    thesis B.3);
//  - release (lambda_n reaches 0 decreasing): the contact opens;
//  - slip onset (mu^2 lambda_n^2 - ||lambda_t||^2 reaches 0): the contact slips against its
//    friction force, d = -lambda_t/||lambda_t|| (planar: the sign);
//  - stop (the slip velocity reaches 0): the acceleration-level choice with that contact at
//    tangential rest decides between stick and slip (the other way round, for planar contacts).
// After a transition, every guard of the new mode is checked at the same instant: one that is
// already below zero, or at zero and decreasing, fires at once (a chain), until none is due or
// `max_chain` transitions have been taken. Guards that fired together (within the simulator's
// simultaneity window) are resolved jointly: one impact problem for all touchdowns.
//
// The input at an event. An event time is located on the >= 0 side of its guard's root, within
// the integrator's root_tolerance * max(1, |t|) before it; the transitions are evaluated with the
// input law at t + twice that (the right limit at the event's resolution), so that an input that
// jumps at the event (a piecewise-constant optimal input whose jump makes a release fire) is seen
// as the motion after the event sees it, not as before the jump (where the released contact
// still carries a positive force: reclosed, released again at the same instant, "events stall").
// For a continuous input the difference is 1e-14 relative. The event keeps its time t.
//
// Mode-dependent input laws. The acceleration-level mode selection is made with the input of the
// mode it selects (select_consistent): a law u(t, x, mode) that switches with the contact mode (a
// reference-spreading controller that turns its feedback on once the plant reaches a reference
// mode) may make the mode chosen under the input of the mode being left inconsistent under its
// own input, a release or a touchdown due at once, and the chain would cycle over events at one
// instant. The selection starts from a mode and keeps the first one consistent under its own
// input; such a law can make two modes consistent (a stance loaded under the stance's input, a
// flight leaving the ground under the flight's). After an impact it starts from the impact's own
// post-impact mode (the contacts it closed, closed): the impact has made the contact, a law that
// switches with the mode applies its post-contact input from then on, and the contact opens
// again only where it would pull under that input (the release guard's rule inside a stance).
// Starting from the mode before the impact instead, a reference-spreading controller whose
// stance starts loaded under the stance's input bounces wherever the flight's input would pull
// the foot (the hopper's touchdowns, docs/refinement.md). A law that ignores the mode selects the
// same mode from either start. Where no mode is consistent because one contact at rest on the surface pulls when
// closed and is pushed in when open, the contact slides on the surface at (almost) zero force
// under the equivalent control (ModeSystem::set_sliding, Filippov's sliding solution).
//
// Painleve's inconsistent configuration (dynamics/impact_without_collision.hpp). Where a selection
// (at the start, after an impact, at a stop) has no solution because its one closed contact slides
// into Painleve's inconsistent configuration, the resolver throws by default; with
// options.painleve.resolution = ImpactWithoutCollision it applies the impact without collision as
// the next transition of the event (guards empty, flagged Transition::impact_without_collision),
// selects the mode at the state after it with the contact at tangential rest, and follows the
// chain from there. The same where a release fires for the one closed contact sliding with
// d = W_nn - mu s W_nt < 0: its normal force -b/d reaches zero as the free normal acceleration b
// does, from above, the end of the closed branch of Painleve's indeterminacy (two modes while
// b > 0: lift-off, or the contact the persistent choice keeps); past it b < 0 and neither mode is
// consistent (opening drives the contact into the surface at once). Default: the contact opens
// (and touches down again after it, an ordinary impact); with the option, the transition of the
// release guard is the impact without collision. Several closed contacts, or a spatial one:
// ContactProblemFailure naming the case (the several-contact impulse is not implemented).
//
// Settled transitions. Contacts whose stick/slip changed at this instant are not changed back at
// the same instant, and a contact released at this instant is not closed again by its touchdown
// guard unless it approaches (resolve() says why in its comments).
// Definitions in transition.hxx (compiled once per scene, saltus/hybrid/instantiate.hpp).
#pragma once

#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/dynamics/impact_without_collision.hpp>
#include <saltus/hybrid/dynamics/jump_map.hpp>
#include <saltus/hybrid/dynamics/mode_selection.hpp>
#include <saltus/hybrid/simulation/mode_system.hpp>
#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <array>
#include <memory>
#include <optional>
#include <vector>

namespace saltus {

template <Scene S>
class TransitionResolver {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  /// Uses options.impact, options.selection, options.max_chain, options.guard_tolerance and
  /// options.rest_velocity. The scene must outlive the resolver.
  TransitionResolver(const S& scene, const SimulationOptions& options);
  TransitionResolver(S&&, const SimulationOptions&) = delete;  // would dangle

  /// How a motion starts at (t0, x0) when no mode is given: the mode chosen from the state, and
  /// the impact at t0 if a touching contact approaches.
  struct Start {
    Mode<nc> mode;
    std::optional<Event<S>> impact;  ///< the initial impact (guards: the touchdowns), if any
    int selection_solutions = 1;     ///< of the initial mode selection (SelectionUniqueness)
    int sliding_contact = -1;        ///< a contact left sliding (select_consistent), -1 when none
  };
  /// Touching contacts (gap within the impact's gap tolerance) that approach impact at t0; those
  /// at rest are candidates for the acceleration-level mode selection; the others are open.
  /// @throws InvalidArgument if x0 penetrates a contact; ContactProblemFailure from the selection.
  Start start(ModeSystem<S>& sys, double t0, const State& x0);

  /// The event at time t from x- (the state just before) in mode_before, starting with the guards
  /// `fired` and following the chain at the same instant (file comment). sys is left in the mode
  /// after the event. `deferred`: guards this chain must not fire, typically guards at zero at
  /// this instant that fire later, or never, in the motion being composed (the conewise gains of
  /// a simultaneous event take the guards one at a time, sensitivity/conewise_gain.hpp); a
  /// deferred touchdown's contact, while open, takes no part in the impact problems of this event.
  /// @throws NumericalFailure when the chain does not settle in max_chain transitions;
  /// ContactProblemFailure from an impact or a mode selection.
  Event<S> resolve(ModeSystem<S>& sys, double t, const State& x_minus, const Mode<nc>& mode_before,
                   std::vector<Guard> fired, const std::vector<Guard>& deferred = {});

  /// The guards of sys's mode due at (t, x): below -tolerance, or within it and decreasing (a
  /// touchdown: approaching faster than the velocity tolerance). Tolerances: the impact's gap
  /// tolerance (touchdown), guard_tolerance times the force scale (release) or its square (slip
  /// onset), the velocity tolerance (stop).
  std::vector<Guard> guards_due(ModeSystem<S>& sys, double t, const State& x);

  /// One transition triggered by `guards` (all at once) at (t, x) in `mode`: updates x (an impact
  /// changes v) and mode, and records the impulse in tr.
  void apply(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode, const std::vector<Guard>& guards,
             Transition<S>& tr);

  /// The state after a known transition of a reference, with the reference's decisions: the jump
  /// map of tr.impulse_mode if it was an impact, x itself otherwise. For re-simulations that must
  /// follow a reference's event (the numerical twin). @throws InvalidArgument for the Zeno
  /// completion of an accumulation (Transition::zeno_completion), which no jump map replays.
  State replay(const Transition<S>& tr, const State& x);

  /// The mode of `base` with the contacts of `chosen` replaced by the acceleration-level selection
  /// over `candidates` (`rest`: ModeSelector::select), chosen under the input of the mode it
  /// returns: from u(t, x, base), re-selected under the input of the selected mode until the mode
  /// repeats (a law that does not depend on the mode: one selection). A two-cycle A -> B -> A whose
  /// modes differ only in contact i, closed in A and open in B, is a sliding contact: returns A
  /// with sys in A and sliding on i (ModeSystem::set_sliding, force floor 4 guard_tolerance times
  /// the force scale), and `sliding` = i (else -1). `solutions`: of the last selection.
  /// @throws NumericalFailure when the law makes no mode consistent otherwise (a longer cycle, or
  /// modes differing in several contacts), naming the modes; ContactProblemFailure from the
  /// selection.
  Mode<nc> select_consistent(ModeSystem<S>& sys, double t, const State& x, const Mode<nc>& base,
                             const std::array<bool, nc>& chosen, const std::array<bool, nc>& candidates,
                             const std::array<bool, nc>& rest, int& solutions, int& sliding);

  /// Painleve's inconsistent configuration in `mode` at x under u (file comment): the one closed
  /// contact of `mode`, with planar friction, touching (gap within [-100, 1] gap tolerances), at
  /// zero normal velocity, slipping along its tangential velocity, with d = W_nn - mu s W_nt <= 0
  /// and free normal acceleration b < 0 (dynamics/impact_without_collision.hpp). Returns that
  /// contact, -1 when `mode` is not such a configuration.
  int inconsistent_slip(const State& x, const Input& u, const Mode<nc>& mode);

  /// The event of the impact without collision at (t, x) of contact `contact`, slipping in `mode`
  /// in Painleve's inconsistent configuration (inconsistent_slip), then the chain at the same
  /// instant as in resolve(). Used for a start in that configuration.
  /// @throws InvalidArgument unless options.painleve.resolution is ImpactWithoutCollision;
  /// ContactProblemFailure from the impulse (impact_without_collision) or the selection after it;
  /// as resolve().
  Event<S> resolve_inconsistent(ModeSystem<S>& sys, double t, const State& x, const Mode<nc>& mode, int contact);

  /// A velocity below this counts as zero at x: selection.velocity_tolerance * max(1, ||v||_inf).
  double velocity_tolerance(const State& x) const;

  const S& scene() const { return scene_; }
  const SimulationOptions& options() const { return options_; }
  ImpactSolver<S>& impact_solver() { return *impact_; }
  ModeSelector<S>& mode_selector() { return selector_; }

 private:
  void apply_impact(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode, const std::vector<Guard>& guards,
                    Transition<S>& tr);

  /// select_consistent, with Painleve's inconsistent configuration left to the caller (file
  /// comment): where the selection throws ContactProblemFailure, options.painleve.resolution is
  /// ImpactWithoutCollision and the one candidate slides into that configuration, sets
  /// painleve_contact_ to it and returns `base` with the chosen contacts open but that one, slipping
  /// along its velocity. @throws the selection's failure otherwise (unchanged under Refuse);
  /// ContactProblemFailure naming the case for several candidates or a spatial contact.
  Mode<nc> select_or_defer(ModeSystem<S>& sys, double t, const State& x, const Mode<nc>& base,
                           const std::array<bool, nc>& chosen, const std::array<bool, nc>& candidates,
                           const std::array<bool, nc>& rest, int& solutions, int& sliding);
  /// The impact without collision of contact i at (t, x): x gets the velocity jump, mode the mode
  /// selected after it (the contact at tangential rest), tr the impulse and the flag.
  void apply_impact_without_collision(ModeSystem<S>& sys, double t, State& x, Mode<nc>& mode, int i,
                                      Transition<S>& tr);
  /// inconsistent_slip; with `at_release`, the release of that contact instead: d < 0 (b reaches
  /// zero from above as the normal force -b/d reaches zero), the sign of b not required.
  int painleve_slip(const State& x, const Input& u, const Mode<nc>& mode, bool at_release);
  /// Contact i's Delassus matrix W (rows n, t), its free normal acceleration b (under u), its
  /// normal and tangential velocities and its gap at x (contact i planar).
  void contact_delassus(const State& x, const Input& u, int i, Eigen::Matrix2d& W, double& b, double& v_n,
                        double& v_t, double& gap);

  const S& scene_;
  SimulationOptions options_;
  /// The contact whose impact without collision is the next transition of resolve() (-1: none).
  int painleve_contact_ = -1;
  /// Open contacts kept out of impact problems: deferred touchdowns of the resolve() under way.
  std::array<bool, nc> deferred_contacts_{};
  std::unique_ptr<ImpactSolver<S>> impact_;  ///< large: on the heap
  ModeSelector<S> selector_;
  FlowWorkspace<S> flow_;
  JumpWorkspace<S> jump_;
};

}  // namespace saltus
