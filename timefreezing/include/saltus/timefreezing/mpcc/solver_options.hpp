// The settings of solve_mpcc (solve.hpp), nested by concern: the homotopy, Ipopt, the warm start,
// the polish by a branch NLP, the progress lines. Defaults follow NOSNOC's where the evidence
// agrees (the relaxation Scholtes, sigma_0 = 1, kappa = 0.1, bound_relax_factor = 0); deviations
// are explained per field. Experiments measured worse and removed: docs/decisions/mpcc-*.md.
#pragma once

#include <iosfwd>
#include <string>
#include <variant>
#include <vector>

namespace saltus::timefreezing {

/// One Ipopt option set by name, passed as is (after the solver's own settings, so it overrides
/// them): e.g. {"linear_solver", "mumps"}, {"acceptable_iter", 3}, {"mumps_pivtol", 1e-4}.
/// Ipopt's option types are strict: an integer option needs an int, a number option a double.
struct IpoptOption {
  std::string name;
  std::variant<std::string, int, double> value;
};

/// Settings of solve_mpcc. validate() checks them (solve_mpcc calls it).
struct MpccSolverOptions {
  /// How a homotopy step relaxes the pairs (solve.hpp, top of file).
  enum class Relaxation {
    Scholtes,  ///< G_j H_j <= sigma_k as constraint rows (the most robust in NOSBENCH's runs)
    /// G_j H_j = sigma_k for the smoothable pairs, <= sigma_k for the others (solve.hpp). Only pairs
    /// the problem marks smoothable are smoothed: FesdMpcc marks its stage-wise pairs, which exist
    /// for the velocities without velocity switch detection and for every switching function
    /// without switch detection; with FESD's defaults there are none and Smoothing is Scholtes
    /// (MpccSolution::smoothed_pairs says how many were smoothed).
    Smoothing,
    Penalty  ///< rho_k sum_j G_j H_j in the objective, rho_k = 1 / sigma_k
  };

  /// The homotopy sigma_0, kappa sigma_0, kappa^2 sigma_0, ... and when it stops.
  struct Homotopy {
    Relaxation relaxation = Relaxation::Scholtes;
    /// First relaxation parameter (Penalty: rho_0 = 1 / sigma_0), > 0. NOSBENCH (Nurkanović,
    /// Pozharskiy, Diehl 2024), section 5.4: sigma_0 in [0.1, 10]; a too small sigma_0 loses
    /// problems to bad local minima.
    double sigma_0 = 1.0;
    /// sigma_{k+1} = kappa sigma_k, kappa in (0, 1).
    double kappa = 0.1;
    /// Converged when a successful step has max_j |G_j H_j| <= this (>= 0).
    double complementarity_tolerance = 1e-9;
    /// Refinement past convergence (0: off; else in [0, complementarity_tolerance]). A product
    /// G_j H_j <= 1e-9 still lets both sides be ~3e-5: in a time-freezing simulation the frozen
    /// phase of an impact, where the gap's pair is degenerate (both sides vanish exactly), then lets
    /// the gap drift to -1.6e-5 and the clock creep 5e-6 (Example 3, n_s = 2: that drift was the
    /// whole final error at 112 elements; bench/README.md, "Where Example 3's error came from";
    /// with the contact-side selection and a target of 1e-14 the same example shows the Radau
    /// order, 1.45e-9 at 112 elements). With a target, a converged homotopy whose polish did not
    /// succeed goes on decreasing sigma while its steps succeed and their residual shrinks, until
    /// the residual is <= this target; the first step that fails (no retries) or does not lower the
    /// residual ends the refinement, and the result is the last successful step, still converged;
    /// so does a step whose constraint violation exceeds the previous step's (or
    /// polish.feasibility_tolerance, whichever is larger). Refinement steps count against
    /// max_steps, are listed in `steps` and are not polished; the message says how many were
    /// accepted and why the refinement ended. A successful polish is exactly complementary
    /// already, so with the polish on this acts only where the polish failed.
    double complementarity_refinement = 0.0;
    /// Number of homotopy steps (sigma values), retries of a step not counted; >= 1.
    int max_steps = 30;
    /// A step whose Ipopt solve fails is restarted from the last successful iterate with a slower
    /// decrease, kappa <- sqrt(kappa), kept for the rest of the homotopy (the failure says the path
    /// needs smaller steps; NOSBENCH section 5.4 and the FESD papers, Nurkanović et al. 2022/2024:
    /// a larger kappa solves more of the hard problems), at most this many times per step; >= 0.
    /// The first step has no iterate to restart from: its failure ends the homotopy.
    int max_step_retries = 3;
    /// A step (and a polish) also counts as successful when Ipopt stops at
    /// Solved_To_Acceptable_Level, or at Search_Direction_Becomes_Too_Small with the original
    /// constraint violation <= small_step_feasibility_tolerance (>= 0); NOSBENCH scores these as
    /// solved.
    bool accept_acceptable = true;
    double small_step_feasibility_tolerance = 1e-8;
  };

  /// Ipopt, per solve. Ipopt's own options are passed through by name (`options`); the solver
  /// sets these first (solver_defaults(); an entry of `options` overrides them):
  /// - mu_strategy = adaptive, mu_oracle = quality-function: what NOSNOC, MPECopt (Nurkanović,
  ///   Leyffer 2025) and the NOSBENCH runs use. With warm-started duals the adaptive oracle starts
  ///   from the small complementarity of the previous solution instead of a large barrier parameter.
  /// - bound_relax_factor = 0: the bounds (among them the sign bounds G, H >= 0 of single-variable
  ///   sides) hold exactly, so products measure complementarity, and sides that the bounds keep
  ///   >= 0 need no row (solve.hpp, "Row pruning"); Ipopt's 1e-8 would let both sides of a pair go
  ///   slightly negative. NOSNOC, MPECopt and NOSBENCH all use 0.
  /// - warm_start_bound_push = warm_start_bound_frac = warm_start_slack_bound_push =
  ///   warm_start_slack_bound_frac = 1e-9, warm_start_mult_bound_push = 1e-6 (used with the warm
  ///   start only): the previous solution sits on its active bounds and Ipopt's default 1e-3 would
  ///   push it away from them, undoing most of the warm start. Measured on the 10-step Scholtes
  ///   homotopy of tests/test_mpcc_solver.cpp (SmallMpcc), total Ipopt iterations with mult push
  ///   1e-6: bound push 1e-3 -> 36, 1e-6 -> 26, 1e-9 -> 24; primal-only starts: 72; with bound push
  ///   1e-9: mult push 1e-3 -> 44, 1e-6 and 1e-9 -> 24 (1e-6 keeps a margin from zero for the
  ///   multipliers Ipopt divides by).
  /// - mumps_mem_percent = 1000 (Ipopt's default, the extra MUMPS workspace in percent of its
  ///   estimate). 100 makes the small FESD solves 25-35 % faster (the frictional landing 6.1 ->
  ///   4.6 s, the same iterates; bench/README.md, "Where a simulation's time goes") but changes
  ///   the iterates of ill-conditioned homotopies (Example 3, n_s = 2, 1,120 elements: final error
  ///   1.07e-7 against 7.65e-9); the plank-box's short landing passes {"mumps_mem_percent", 100}.
  struct IpoptSettings {
    /// Ipopt `tol` (> 0). For OCPs 1e-8 with the Penalty relaxation is much faster (point-mass
    /// time-freezing OCP, N = 10, Scholtes: 1e-10 cycles at mu = 1e-11 for hundreds of iterations,
    /// 6368 iterations in all against 1976 with 1e-8; Penalty with 1e-8: 422); the FESD
    /// simulations need 1e-10 (with 1e-8 the guiding example's homotopy fails in one control
    /// interval), so the default stays 1e-10 (solve_time_freezing_ocp's docstring).
    double tol = 1e-10;
    int max_iter = 3000;  ///< Ipopt `max_iter` per homotopy step (>= 0)
    int print_level = 0;  ///< Ipopt `print_level` (0..12); 0: no Ipopt output at all
    /// Ipopt's options by name, applied last (an entry "max_iter" replaces max_iter for the
    /// homotopy's steps). An option Ipopt rejects throws InvalidArgument.
    std::vector<IpoptOption> options;

    /// The options the solver sets before `options` (the list above), in the order it sets them.
    static std::vector<IpoptOption> solver_defaults();
  };

  /// The branch NLP (BNLP) after a successful step (solve.hpp, "Polishing").
  struct Polish {
    /// Try the branch NLP after the successful steps with residual <= below and after the last
    /// successful step; stop at the first polish that succeeds. (Not saltus::polish() of
    /// hybrid/reference/resimulation.hpp, which re-simulates an imported reference.)
    bool enabled = true;
    /// >= 0. Default 0: polish only after the homotopy's last successful step. Early polishing
    /// (1e-6) saves steps on small problems (tests: SmallMpcc 22 instead of 24 iterations) but on
    /// the chained FESD simulation of time-freezing Example 3 (4 elements, 2 Radau stages) a
    /// polish at sigma = 1e-6 guesses branches the homotopy has not resolved yet; the exact but
    /// different interval end states then led a later interval to a worse local solution and an
    /// infeasible one after it (not converged, 55000 Ipopt iterations against 4255). The
    /// plank-box flagship polishes from 1e-4 (its scene's settings).
    double below = 0.0;
    /// The polished point's largest violation of the original constraints (bounds, g, the sides'
    /// signs) for the polish to count (>= 0).
    double feasibility_tolerance = 1e-8;
    /// Ipopt `max_iter` of a polish (>= 0). From the warm start, a right guess converges in a few
    /// iterations; a wrong one can wander for thousands (FESD time-freezing, Example 3: 3000).
    int max_iter = 100;
    /// The polish is rejected when its objective exceeds the step's by more than
    /// 2 sum_j w_j |G_j H_j| + objective_increase * max(1, |f_step|) (>= 0), w_j the pair's weight
    /// in the step's Lagrangian (Scholtes: the relaxation row's multiplier; Penalty: rho): the
    /// relaxed optimum lies about sum_j w_j |G_j H_j| below the MPCC's, more means the branch NLP
    /// found another, worse local solution (a wrong or premature guess of the branch).
    double objective_increase = 1e-4;
  };

  Homotopy homotopy;
  IpoptSettings ipopt;
  /// Warm start every step but the first from the previous successful step's primal AND dual
  /// solution (x, constraint multipliers including the relaxation rows, z_L, z_U), with Ipopt's
  /// warm_start_init_point = yes; the polish likewise from its step's. false: each solve starts
  /// from the previous x only, with Ipopt's own initialisation of the multipliers and its default
  /// push away from the bounds (NOSNOC's default, warm_start_duals = false).
  bool warm_start = true;
  Polish polish;
  /// One line per Ipopt solve (homotopy step or retry) when not null: step, sigma (or rho),
  /// complementarity residual, objective, constraint violation, Ipopt iterations and status,
  /// seconds, and for a failed step the row its iterate violates most ("worst: ...",
  /// MpccHomotopyStep::worst_violation); per polish the branch, why it failed and, when its
  /// violation exceeds polish.feasibility_tolerance, its worst row. Not owned; must outlive the
  /// call.
  std::ostream* progress = nullptr;

  /// Throws InvalidArgument naming the first field out of its domain.
  void validate() const;
};

}  // namespace saltus::timefreezing
