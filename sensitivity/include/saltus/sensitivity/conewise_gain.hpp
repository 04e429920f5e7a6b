// Conewise-linear, positively homogeneous jump gains of simultaneous events (thesis C.40-C.63
// and appendix D; Rijnen, Chen, van de Wouw, Saccon, Nijmeijer 2018).
//
// Shapes and units: z- (nx = 2 nq) is the state deviation (q, q') from the extended ante-event
// reference at the nominal event time t*, v (nu) the input deviation at t*, z+ (nx) the deviation
// from the post-event reference at t* (the nominal one, or the piece's own outcome, below); all in
// the scene's units (SI in the library's scenes). The map is H(z-, v) = G_z z- + G_v v on the cone
// of the piece that contains (z-, v).
//
// An event fired by m guards at once (a box landing flat: both corners' touchdowns) is split by a
// perturbation into m micro-events in an order that depends on the perturbation. To first order
// the map from the ante-event deviation (z-, v) to the post-event deviation z+ is then linear on
// each of finitely many polyhedral cones and positively homogeneous: H(a z, a v) = a H(z, v) for
// a > 0. Each linear piece is the sequential composition of single-guard gains (jump_gain.hpp)
// through the intermediate modes.
//
// Derivation (the draft thesis states D.2-D.8 and C.40-C.60; written out here with the
// intermediate references made explicit). Let the nominal event happen at t* from x- in mode s0,
// with guards gamma_1..gamma_m all at zero. Call node N a state x_N at t* with a mode s_N reached
// by applying some of the guards' micro-events one at a time (node 0: x-, s0), and its
// intermediate reference the flow of s_N through (t*, x_N), extended both ways. A perturbed
// motion that has seen the micro-events of N is x_N-reference + eps z_N + o(eps), z_N linear in
// (z-, v): z_N = Z_N z- + V_N v. For each guard i not yet fired and crossing at N (gamma_dot_i < 0
// along s_N's flow), the perturbed motion crosses it at t* + eps dt_i with (C.22 along s_N)
//     dt_i = -(Dgamma_i,x z_N + Dgamma_i,u v) / gamma_dot_i,
// and the next micro-event is the earliest: j = argmin_i dt_i (D.4-D.8). On the cone where j is
// the argmin, i.e. dt_i - dt_j >= 0 for every other crossing i (linear inequalities in (z-, v)),
// the motion takes micro-event j: the event physics resolves the transition fired by gamma_j alone
// at (t*, x_N) (the impact problem and the acceleration-level mode selection at that intermediate
// state, never assumed; the guards still to come are held back and their contacts kept out of the
// impact problem: in the perturbed motion they are at a positive gap of order eps), following its
// own chain (an impact into stick that slips at once). The single-guard gain of that step, with
// dt_j computed from z_N exactly as above (JumpGainSolver on the step's transitions), maps z_N to
// z_{N'} of the next node N' (C.40-C.42):
//     z_{N'} = G_z,step z_N + G_v,step v.
// A leaf (no guard left that crosses) is a piece: G_z = Z_leaf, G_v = V_leaf, and its cone is the
// conjunction of the argmin inequalities along its path. The cones of the leaves cover (z-, v)
// space and overlap only on faces; that dt_i >= dt_{previous} holds on the cone (a guard not yet
// fired is not below zero when the previous micro-event happens) follows for guards that are
// continuous across the jumps (touchdowns: the gap is), and is what a simulator does anyway.
//
// Orders that cannot happen. A guard whose rate is positive at a node (gamma_dot_i > 0: the
// previous impulse sends the contact away from the surface) cannot be the next micro-event: the
// orders that put it next cannot happen. It is reported (UnrealisableOrder::Reason::SentAway) and
// left out of the node's competition; every node classifies the guards afresh (a later impulse
// may turn the contact back; "Re-touchdowns" below), and a leaf where it still does not cross
// ends with that contact open, a post-event mode the nominal event may not have
// (`nominal_outcome`). An
// order whose cone has no interior (the argmin inequalities along its path admit only a set of
// measure zero: the fourth corner of a box face comes down with the third, so the corner
// diagonal to the first is never the second to land) is reported too (Reason::EmptyCone, by
// Gordan's alternative: the origin lies in the convex hull of the normalised rows, to
// empty_cone_tolerance; Wolfe's nearest point, detail/dense.hpp) and not built. More generally a piece whose post-event
// state or mode differs from the nominal one (for instance sequential frictional impacts that end
// sliding: the tangential velocity depends on the order) has no nominal post-event reference:
// its z+ is the deviation from its own post-event state x_plus. Reference spreading has no
// extended segment for that mode, so a tracking controller would have to switch to a reference it
// does not have; the prediction is first-order only up to the event (LinearisedSystem refuses to
// carry such a piece beyond it, with an exception naming the order).
//
// Coincident guards (the same first-order crossing-time shift as a function of (z-, v), e.g.
// the stop guards of redundant contacts) are grouped at each node and fire as one micro-event:
// no perturbation separates them. An event whose guards all coincide has one piece, a linear gain
// (JumpGainSolver computes it directly).
//
// Assumptions checked, each a clear exception naming the order so far and the guard:
//  - every crossing is transversal: |gamma_dot_i| > grazing_threshold * rate scale at every node
//    (GrazingEvent), including the first node (each guard of the event must cross there);
//  - every micro-event's chain settles and its impact problem is solved (the event physics'
//    exceptions, with the order added to the message);
//  - continuity across shared faces is measured, not assumed: face_discontinuity().
//
// Re-touchdowns. A guard may fire more than once within the macro-event: a corner that landed
// (its contact closed) is released by a later impulse (the impact problem at that intermediate
// state gives it a positive normal velocity: its mode is open again, its touchdown guard exists
// again with rate > 0: `away`, held back like a contact sent away), and a still later impulse
// can turn its normal velocity negative: it lands again. Nothing new is needed for the first
// order: at every node each of the event's guards whose contact is open is classified afresh as
// above. The released contact's gap is zero to zeroth order (it was closed at t*) and its
// first-order deviation Dgamma_i z_N already carries the time it spent moving away (z_N is
// composed through every micro-event's saltation, its dt included), so dt_i computed from z_N
// is its re-crossing time and exceeds the previous micro-event's on the cone (the gap was
// positive in between). A contact released with zero normal velocity (opened by the mode
// selection at the acceleration level) leaves at second order and is held back, not reported
// as grazing. The spatial box landing flat on four corners does this: each corner lands twice,
// 7-8 micro-events per piece, ending on one corner with the others moving away at 0.5-12 mm/s
// (they land again about 0.2 ms later and more: zeroth-order times, events of their own). A
// cascade that would not end (Zeno-like at first order, or a cycle of releases) is stopped at
// options.max_micro_events with NumericalFailure naming the order so far.
//
// Cost: up to m! leaves. The tree is built lazily: evaluate() builds only the nodes on the path
// of its (z-, v) and keeps them (memoised); build_all() builds every leaf. A node costs one
// resolved transition (impact problem, mode selection), one single-guard gain and one guard
// crossing per remaining guard.
// Definitions in conewise_gain.hxx (compiled per scene, saltus/sensitivity/instantiate.hpp).
#pragma once

#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/sensitivity/jump_gain.hpp>

#include <limits>
#include <memory>
#include <vector>

namespace saltus {

template <Scene S>
class TransitionResolver;

struct ConewiseGainOptions {
  /// The single-guard gains of each micro-event (grazing threshold, feedback treatment, ...).
  JumpGainOptions gains;
  /// The event physics (impact options, mode selection, chain length, guard tolerances): use
  /// those of the simulation that produced the reference.
  SimulationOptions simulation;
  /// A piece's post-event state is the nominal one when max |x_plus - x+| <= this * max(1, |x+|).
  double outcome_tolerance = 1e-9;
  /// A cone whose certified margin (the smallest normalised row at its deepest direction found:
  /// the nearest point of the rows' convex hull to the origin, Wolfe's algorithm) is not above
  /// this has no interior (its order is unrealisable, UnrealisableOrder::Reason::EmptyCone).
  /// Checked for every cone; in (0, 1).
  double empty_cone_tolerance = 1e-9;
  /// The most micro-events on one path of the tree, re-touchdowns included; a path still
  /// crossing guards beyond it throws NumericalFailure (a Zeno-like cascade at first order).
  int max_micro_events = 64;
};

/// One linear piece of a conewise jump gain: z+ = G_z z- + G_v v on the cone
/// {(z-, v): cone_z z- + cone_v v >= 0}.
template <Scene S>
struct ConewisePiece {
  static constexpr int nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  /// The micro-events in the order they happen in this cone, each the group of the event's
  /// guards it fires: one guard, or several that coincide (they fire together in every nearby
  /// motion: "Coincident guards" in jump_gain.hpp).
  std::vector<std::vector<Guard>> order;
  std::vector<Guard> never_crossed;  ///< the event's guards a motion in this cone does not cross near t*
  Mat<nx, nx> G_z = Mat<nx, nx>::Identity();
  Mat<nx, nu> G_v = Mat<nx, nu>::Zero();
  /// One row per argmin comparison along the order (dt_i - dt_j >= 0, for each other group
  /// crossing at that node): (m - 1) + (m - 2) + ... rows when every guard fires once, more
  /// with re-touchdowns (the spatial box's pieces: 10).
  Eigen::Matrix<double, Eigen::Dynamic, nx> cone_z;
  Eigen::Matrix<double, Eigen::Dynamic, nu> cone_v;
  /// The direction (z-, v) deepest inside the cone (unit Euclidean norm, z- first), and its
  /// margin: every normalised row is >= interior_margin there, so the ball of that radius around
  /// it lies in the cone (the nearest point of the normalised rows' convex hull to the origin,
  /// detail/dense.hpp). A piece without rows (one piece: every guard coincident) has the first
  /// unit vector and an infinite margin. Where a one-sided perturbation of this piece is drawn
  /// (numerical_conewise_piece).
  Eigen::Matrix<double, nx + nu, 1> interior_direction = Eigen::Matrix<double, nx + nu, 1>::Unit(0);
  double interior_margin = std::numeric_limits<double>::infinity();
  Vec<nx> x_plus = Vec<nx>::Zero();  ///< post-event state of this order at t* (zeroth order)
  Mode<nc> mode_after{};
  /// x_plus and mode_after are the nominal event's (within outcome_tolerance): z+ is then the
  /// deviation from the nominal post-event reference.
  bool nominal_outcome = true;
  double post_state_difference = 0.0;  ///< max |x_plus - nominal x+|
  /// The micro-events of this order as the event physics resolved them (each with its chain).
  std::vector<Event<S>> steps;
  double build_seconds = 0.0;  ///< wall time (steady clock) spent on the nodes of this piece's path, root included

  /// True if (z, v) lies in the cone: every row, normalised, gives >= -tolerance * |(z, v)|.
  bool contains(const Vec<nx>& z, const Vec<nu>& v, double tolerance = 0.0) const;
};

/// Orders of the event's guards that no open set of nearby motions realises: after the
/// micro-events `fired` (flattened, in order), `next` cannot be the next micro-event.
struct UnrealisableOrder {
  enum class Reason {
    SentAway,        ///< its rate is positive: the impulses so far send the contact away
    NoLongerAGuard,  ///< the contact's mode changed so that the guard no longer exists
    EmptyCone        ///< the perturbations that would fire it next form a cone without interior
  };
  std::vector<Guard> fired;
  std::vector<Guard> next;
  Reason reason = Reason::SentAway;
  double gamma_dot = 0.0;  ///< of `next` after `fired` (SentAway)
};

/// The conewise jump gain of one simultaneous event (file comment).
template <Scene S>
class ConewiseJumpGain {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = Vec<nx>;
  using Input = Vec<nu>;
  using Piece = ConewisePiece<S>;

  /// The event's first transition must be fired by guards (one or more); its x- and mode before
  /// are the nominal ones; `law` is the input law of the reference (copied: the scene, and what
  /// the law captures, must outlive this object). options.simulation must be the reference's own
  /// simulation options: other impact or selection options can resolve the micro-events
  /// differently. @throws InvalidArgument (an event without guards, an empty law, a guard of the
  /// event that its mode does not have, options out of range: outcome_tolerance < 0,
  /// empty_cone_tolerance outside (0, 1), max_micro_events < 1), GrazingEvent (a guard of the
  /// event that does not cross transversally at x-, or whose rate is positive there).
  ConewiseJumpGain(const S& scene, const Event<S>& event, const InputLaw<S>& law, ConewiseGainOptions options = {});
  ConewiseJumpGain(S&&, const Event<S>&, const InputLaw<S>&, ConewiseGainOptions = {}) = delete;  // would dangle
  ~ConewiseJumpGain();
  ConewiseJumpGain(ConewiseJumpGain&&) noexcept;

  /// The guards of the event's first transition (m of them), and the event.
  const std::vector<Guard>& guards() const { return guards_; }
  const Event<S>& event() const { return event_; }
  double t() const { return event_.t; }

  /// The piece whose cone contains (z-, v), built on first use. Ties (a face) go to the guard
  /// listed first in guards(): the map is continuous there when face_discontinuity() is small.
  /// A cone found empty (interior below empty_cone_tolerance) is never returned: on its
  /// measure-zero set the next earliest micro-event's piece is, whose cone then contains (z, v)
  /// up to that tolerance. @throws InvalidArgument (non-finite z or v), GrazingEvent (an
  /// intermediate crossing that is not transversal), the event physics' exceptions
  /// (ContactProblemFailure, NumericalFailure, NonSpdMassMatrix), SimultaneousActivation (a
  /// micro-event's chain fired by several non-coincident guards at once), NumericalFailure (a
  /// path longer than max_micro_events), each naming the order so far; InternalError if every
  /// cone of a node were empty (cannot happen: they cover space). Allocates only when it builds.
  const Piece& piece(const State& z_minus, const Input& v);
  /// z+ = G_z z- + G_v v of piece(z-, v).
  State evaluate(const State& z_minus, const Input& v);
  State evaluate(const State& z_minus) { return evaluate(z_minus, Input::Zero()); }

  /// Builds every piece (at most m! leaves without re-touchdowns). Returns the number of pieces.
  /// @throws as piece(), and NumericalFailure for a path longer than max_micro_events.
  int build_all();
  /// The pieces built so far, in the order they were built.
  const std::vector<const Piece*>& pieces() const { return pieces_; }
  /// Orders found impossible so far (build_all() finds all of them).
  const std::vector<UnrealisableOrder>& unrealisable_orders() const { return unrealisable_; }

  /// Continuity across shared cone faces, measured: `samples` random directions (z-, v) (unit
  /// Euclidean norm in the scene's units, seeded) are projected onto each face of their piece's
  /// cone; where the projection p lies on the cone's boundary, the neighbouring piece across that
  /// face is found by a step of 1e-7 |p| outward and both pieces are applied at p. Returns
  /// max |H_a(p) - H_b(p)| / |p| over the pairs of pieces with the same post-event outcome, and
  /// the number of face points compared in `faces` (0: none compared: a single piece, pieces
  /// with different outcomes, or faces the samples missed). Builds the pieces it meets.
  double face_discontinuity(int samples, int* faces = nullptr, unsigned seed = 20261130);

 private:
  struct Node;
  // The child of `node` for its crossing group k, built on first use; null when its cone has no
  // interior (recorded in unrealisable_).
  Node* child(Node& node, int k);
  void classify(Node& node);
  std::string describe_order(const std::vector<Guard>& fired) const;

  const S& scene_;
  Event<S> event_;
  InputLaw<S> law_;
  ConewiseGainOptions options_;
  std::vector<Guard> guards_;
  std::unique_ptr<TransitionResolver<S>> resolver_;
  std::unique_ptr<JumpGainSolver<S>> gains_;
  std::unique_ptr<Node> root_;
  std::vector<const Piece*> pieces_;
  std::vector<UnrealisableOrder> unrealisable_;
};

}  // namespace saltus
