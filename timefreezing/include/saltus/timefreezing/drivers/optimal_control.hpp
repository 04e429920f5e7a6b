// The time-freezing optimal-control drivers: build the FESD MPCC of an OCP, solve it by the MPCC
// homotopy (from the initial state, a guess, or a continuation on the OCP's data), and recover the
// result in physical time. Declared here, defined in optimal_control.hxx: a program that includes
// this header links the drivers from the translation unit that instantiates them for its scene and
// OCP (saltus/timefreezing/instantiate.hpp), or includes <saltus/timefreezing/header_only.hpp>.
#pragma once

#include <saltus/timefreezing/drivers/simulate.hpp>

#include <vector>

namespace saltus::timefreezing {

/// The result of solve_time_freezing_ocp.
template <Scene S>
struct TimeFreezingOcpResult {
  static constexpr int nx = 2 * S::nq;
  using Point = typename FesdMpcc<S>::Point;
  MpccSolution solution;       ///< converged, complementarity, objective, steps, iterations, seconds
  std::vector<Point> points;   ///< the discrete solution in numerical time
  std::vector<double> element_lengths;
  std::vector<FrozenPhase<nx>> frozen_phases;  ///< the impacts
  std::vector<SwitchPoint> switch_points;      ///< touchdowns, lift-offs, slip-stick
  /// The samples of `trajectory` at the element boundaries with the discrete control, for polish()
  /// (recover_reference).
  ImportedReference<S> reference;
  /// Recovered in physical time (recover_trajectory); when not converged(), only a reading of the
  /// unconverged points, not a motion of the scene.
  HybridTrajectory<S> trajectory;
  /// solve_time_freezing_ocp_by_continuation: one relaxed NLP per continuation stage, in order
  /// (their iterations and seconds are included in solution.ipopt_iterations and seconds).
  std::vector<MpccHomotopyStep> continuation_steps;
  bool converged() const { return solution.converged; }
};

/// Solves the time-freezing OCP described by `ocp` (formulation/ocp.hpp lists what it may
/// provide) from (q0, v0) with FESD, by the MPCC homotopy, and recovers its reference in physical
/// time. Returns the result whether or not the homotopy converged (converged() says; the message
/// says why not). Throws InvalidArgument for bad options or states.
/// Solver settings, measured on the point mass landing and sliding to a target (N = 10, N_fe = 3):
/// the defaults (Scholtes, tol 1e-10) took 6368 Ipopt iterations; tol = 1e-8 with
/// relaxation = Penalty took 422 (two homotopy steps and the polish) and found the cheaper of
/// the two local optima (18.8 against 35.2). Known limit: at a touchdown inside an element the
/// gap's switching function is exactly 0, its multipliers vanish and cross-complementarity cannot
/// stop the active set from changing inside that element; such an impact is not a frozen run of
/// elements: the recovery reads it as an impact absorbed into a flowing element, its x+ off by the
/// motion over the clock's advance (recover_trajectory.hpp).
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp(const TimeFreezingSystem<S>& system, const Ocp& ocp, const Vec<S::nq>& q0,
                                                 const Vec<S::nq>& v0, const FesdOptions& fesd,
                                                 const MpccSolverOptions& solver = {});

/// solve_time_freezing_ocp from a guess of the motion instead of the initial state at every stage
/// point: `guess(t)` -> Vec<2 nq> (q, v) at physical time t (FesdMpcc::initial_point_from_guess
/// says how the stage points, step functions and multipliers are set from it). A guess is a
/// second initialisation, e.g. a gait whose contact timing the user knows; the contact-implicit
/// setting is solve_time_freezing_ocp. Throws InvalidArgument as solve_time_freezing_ocp and for a
/// guess that is not finite.
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_from_guess(const TimeFreezingSystem<S>& system, const Ocp& ocp,
                                                            const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                            const FesdOptions& fesd, const MotionGuess& guess,
                                                            const MpccSolverOptions& solver = {});

/// A continuation on the OCP's data before the homotopy: the relaxed NLP at the first relaxation
/// parameter solver.homotopy.sigma_0 is solved for each OCP of `continuation` in turn (one homotopy step
/// each, no polish), the first from FesdMpcc's initial point and each later one from the previous
/// one's primal-dual solution (the same Ocp type on the same grid: the problems have the same
/// variables, only bounds or data differ); then the whole homotopy runs on `ocp` from the last of
/// them. E.g. the hopper over three holes (scenes/hopper_holes.hpp): the holes grow from nothing
/// (hole level 1e-4) to their size while the relaxation is loose, so the iterates never face a
/// full hole across the straight path from the start to the target (without it: Ipopt's
/// Infeasible_Problem_Detected in the first step, the foot stopped at a hole's edge).
/// What can vary: the Ocp's own data (bounds of its path and terminal rows, targets, costs); the
/// grid and the control bounds are FesdOptions, one for all stages. Each stage is solved at
/// sigma_0 only (Penalty: rho_0). Its Ipopt solves are in continuation_steps, not in
/// solution.steps, and counted in solution.ipopt_iterations and seconds.
/// A continuation stage that Ipopt does not solve (its status in continuation_steps) ends the
/// continuation: the homotopy then starts from that stage's iterate (or from the last successful
/// one), and the result says so in solution.message. Throws InvalidArgument as
/// solve_time_freezing_ocp, and for an empty continuation.
template <Scene S, class Ocp>
TimeFreezingOcpResult<S> solve_time_freezing_ocp_by_continuation(const TimeFreezingSystem<S>& system,
                                                                 const std::vector<Ocp>& continuation, const Ocp& ocp,
                                                                 const Vec<S::nq>& q0, const Vec<S::nq>& v0,
                                                                 const FesdOptions& fesd,
                                                                 const MpccSolverOptions& solver = {});

}  // namespace saltus::timefreezing
