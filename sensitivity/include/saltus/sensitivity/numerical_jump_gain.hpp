// The numerical twin of the jump gain (jump_gain.hpp): the same G_z, G_v by central differences
// through re-simulation with event detection, with no derivative of a guard, a flow or a jump map.
//
// Around the event at t*, with a window w:
//   x_a = the ante-event mode's flow integrated back from (t*, x-) to t* - w (events off: the
//         extended ante-event reference of reference spreading);
//   P   = d x(t* + w) / d x(t* - w): the Simulator (event detection, the reference's input law and
//         breakpoints) run from x_a +- h e_j in the ante-event mode through the event;
//   Phi- = d x(t*) / d x(t* - w) of the ante-event mode's smooth flow, Phi+ = d x(t* + w) / d x(t*)
//         of the post-event mode's (DormandPrinceIntegrator with detect_events = false).
// To first order P = Phi+ G_z Phi-, so G_z = Phi+^{-1} P Phi-^{-1}. The same runs' event times
// give the event-time shift dt_dz Phi- (and dt_dv below). For G_v the input is perturbed
// by a constant v over the window: with Psi- = d x(t*) / dv and Psi+ = d x(t* + w) / dv of the
// smooth flows and P_v = d x(t* + w) / dv of the simulation,
//     P_v = Phi+ (G_z Psi- + G_v) + Psi+   =>   G_v = Phi+^{-1} (P_v - Psi+) - G_z Psi-.
//
// Closed contacts. When the ante-event mode has closed contacts, only perturbations that respect
// them (gap, normal velocity, and tangential velocity if sticking, unchanged to first order) are
// physical: a perturbed normal velocity in contact makes a released contact fall back at once,
// and the re-simulation chatters. The twin then perturbs x_a along an orthonormal basis T_a of
// the admissible directions (the kernel of the constraints' Jacobian, by central differences),
// projects each perturbed state back onto the constraints (Gauss-Newton), and returns G_z on the
// image B = Phi- T_a: G_z B = Phi+^{-1} P T_a. G_v needs G_z Psi- only, and Psi- lies in that image
// (the flow of a closed mode keeps its constraints). The analytic G_z is compared on B.
//
// Every perturbed run must end in the reference's post-event mode. If the Simulator's run fails
// (or ends elsewhere), the run is replayed with the reference's transitions: event detection by
// the integrator in each mode of the chain, the transition's jump map, the post-event flow (the
// count is returned in `replays`). If that fails too: NumericalFailure (make the steps or the
// window smaller).
//
// Accuracy: Richardson-extrapolated central differences of step h carry O(h^4) truncation and
// O(tol / h) integration noise; h = 1e-4 with integrator tolerances 1e-13 gives ~1e-8..1e-9
// relative. Cost: 4 (nx + nu) hybrid simulations plus 4 (nx + nu) smooth integrations on each
// side (half without Richardson).
#pragma once

#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/jump_gain.hpp>

#include <limits>

namespace saltus {

struct NumericalJumpGainOptions {
  /// The simulation settings of the reference (tolerances, breakpoints, impact options).
  SimulationOptions simulation;
  /// s: half-width w of the window around the event; shrunk to a quarter of the distance to the
  /// neighbouring events and to the ends of the trajectory.
  double window = 1e-3;
  /// Central-difference steps, relative to max(1, |x_j|) and max(1, |u_j|).
  double state_step = 3e-5;
  double input_step = 3e-5;
  /// Richardson extrapolation of every central difference, (4 D(h/2) - D(h)) / 3: O(h^4)
  /// truncation. The hopper's light leg makes second derivatives of the event large, so plain
  /// O(h^2) differences stop at ~1e-5 relative.
  bool richardson = true;
  /// When the Simulator's run through the event fails (NumericalFailure), replay the reference's
  /// transitions with event detection instead (see numerical_jump_gain).
  bool replay_on_failure = true;
  /// numerical_conewise_piece: the size of the one-sided perturbations (their (z-, v) norm),
  /// relative to max(1, |x-|). Its micro-events are then this far apart in time, times the
  /// inverse approach speeds: keep it well above the simulation's event-time tolerance.
  double cone_step = 1e-4;
};

/// The twin's result. `basis` (nx x r) spans the admissible ante-event deviations at t* (r = nx
/// when the ante-event mode has no closed contact); G_z_basis = G_z basis. G_z itself is only
/// determined when r = nx (`full`); G_v always.
template <Scene S>
struct NumericalJumpGain {
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  using Basis = Eigen::Matrix<double, nx, Eigen::Dynamic, 0, nx, nx>;
  bool full = false;
  Mat<nx, nx> G_z = Mat<nx, nx>::Constant(std::numeric_limits<double>::quiet_NaN());
  Basis basis, G_z_basis;
  Mat<nx, nu> G_v = Mat<nx, nu>::Zero();
  /// The first-order event-time shift: dt = dt_basis c for z- = basis c, and dt_dv (the
  /// analytic gain's dt_dz basis and dt_dv), from the perturbed runs' (first) event times.
  Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, nx> dt_basis;
  Eigen::Matrix<double, 1, nu> dt_dv = Eigen::Matrix<double, 1, nu>::Zero();
  double window = 0.0;  ///< the half-width w used
  int replays = 0;      ///< perturbed runs that needed the replay (Simulator failures)
};

/// G_z, G_v of event `e` of `traj` by re-simulation. An event fired by several coincident guards
/// (every perturbed run fires them together: a flat box's two corners stopping together) has its
/// linear gain, as JumpGainSolver's. @throws NumericalFailure, InvalidArgument,
/// SimultaneousActivation (several guards that a perturbed run fires apart: the gain is conewise,
/// numerical_conewise_piece)
template <Scene S>
NumericalJumpGain<S> numerical_jump_gain(const S& scene, const HybridTrajectory<S>& traj, int e,
                                const NumericalJumpGainOptions& options = {});

/// The result of numerical_conewise_piece (below).
template <Scene S>
struct NumericalConewisePiece {
  static constexpr int nx = 2 * S::nq, nu = S::nu;
  Mat<nx, nx> G_z = Mat<nx, nx>::Zero();
  Mat<nx, nu> G_v = Mat<nx, nu>::Zero();
  Eigen::Matrix<double, nx + nu, 1> centre = Eigen::Matrix<double, nx + nu, 1>::Zero();  ///< c
  double radius = 0.0;  ///< r
  double step = 0.0;    ///< s (absolute, in (z-, v) norm)
  double window = 0.0;  ///< the half-width w used
  int runs = 0;         ///< hybrid simulations through the macro-event
};

/// The numerical twin of one piece of a conewise jump gain (conewise_gain.hpp): its G_z (nx x nx)
/// and G_v (nx x nu) by one-sided differences with every perturbation inside the piece's cone,
/// through re-simulation of the whole macro-event (every micro-event located by the simulator;
/// no derivative of a guard, a flow or a jump map).
///
/// Method. Work in the cone's own coordinates p = (z-, v) at t*: a perturbation p of size s
/// starts the simulation at x_a + s Phi-^{-1} (z- - Psi- v) at t* - w with the input shifted by
/// s v over the window (Phi-, Psi- of the ante-event mode's smooth flow, as numerical_jump_gain),
/// so that the deviation reaching t* is s z- and the input's s v. To first order the state at
/// t* + w is then X(s p) = X_piece + s (Phi+ (G_z z- + G_v v) + Psi+ v) + O(s^2), with X_piece,
/// Phi+ and Psi+ from the piece's OWN post-event state x_plus and mode (its outcome, nominal or
/// not). The map is linear on the cone only, so both points of each difference lie inside it:
/// around the cone's deepest direction c (ConewisePiece::interior_direction, margin m),
///     D_j(s) = (X(s (c + r e_j)) - X(s (c - r e_j))) / (2 r s),   r = min(m, 1) / 2,
/// for each unit vector e_j of (z-, v); D_j(s) = M e_j + O(s), and the Richardson combination
/// 2 D_j(s/2) - D_j(s) removes the O(s) term (options.richardson). Then
///     G_z = Phi+^{-1} M_z,   G_v = Phi+^{-1} (M_v - Psi+).
/// Every run must fire the piece's micro-events in the piece's order (a coincident group as one
/// event or several) and end in its post-event mode (the contact modes compared, not a slip's
/// direction): otherwise NumericalFailure naming what the run did (a step that leaves the cone,
/// or a window that holds other events: make cone_step or the window smaller). The window is
/// shrunk to the reference's neighbouring events only: a piece whose own outcome is not the
/// nominal one may have events of its own soon after t* (the spatial box's corners that land
/// again ~0.2 ms later), which the window must not reach.
///
/// Accuracy: O(s^2) truncation after Richardson and O(tol / (r s)) integration noise; with the
/// defaults (s = 1e-4, tolerances 1e-13) ~1e-7 relative. Cost: 4 (nx + nu) hybrid simulations
/// through the macro-event (2 (nx + nu) without Richardson) plus the smooth flows' differences.
///
/// Preconditions: `piece` belongs to the conewise gain of event `e` of `traj` (ConewiseJumpGain
/// built from that event, that law and these simulation options); the ante-event mode has no
/// closed contact (every flat landing: the perturbations are then unconstrained; any event with a
/// closed contact before it is refused with InvalidArgument: numerical_jump_gain handles those
/// for single-guard events).
/// @throws InvalidArgument (index, options, closed contacts before the event, a piece not built
/// from this event: its first micro-event does not start at the event's t* and x-),
/// NumericalFailure (a run that fails, starts inside the surface because the step exceeds the
/// gaps at t* - w, or does not follow the piece)
template <Scene S>
NumericalConewisePiece<S> numerical_conewise_piece(const S& scene, const HybridTrajectory<S>& traj, int e,
                                                   const ConewisePiece<S>& piece,
                                                   const NumericalJumpGainOptions& options = {});

}  // namespace saltus
