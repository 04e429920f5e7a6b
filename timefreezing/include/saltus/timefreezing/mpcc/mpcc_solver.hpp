// The solver of the MPCCs of mpcc.hpp: a homotopy of relaxed (or penalised) NLPs, each solved by
// Ipopt (3.11, MUMPS), as NOSNOC does (/work/shared/research/nosnoc_facts.md section 3 and
// mpcc_robustness.md; S. Scholtes, "Convergence properties of a regularization scheme for
// mathematical programs with complementarity constraints", SIAM J. Optim. 11(4):918-936, 2001):
//
//   Scholtes (inequality form; NOSNOC's SCHOLTES_INEQ): step k solves
//       min f(x)   s.t.  g_lower <= g(x) <= g_upper,  x_lower <= x <= x_upper,
//                        G_j(x) >= 0,  H_j(x) >= 0,  G_j(x) H_j(x) <= sigma_k       (all pairs j)
//   Smoothing: as Scholtes, but the pairs marked `smoothable` (mpcc.hpp) get the EQUALITY
//       G_j(x) H_j(x) = sigma_k (Scholtes' equality form, NOSNOC's SCHOLTES_EQ, restricted to the
//       pairs where it is well posed); the others keep G_j H_j <= sigma_k. Why: under the
//       inequality a relaxed FESD time-freezing NLP leaves every step function free in a band
//       (alpha in [0, 1] wherever |c| < sigma / lambda), a continuum of equally good solutions that
//       Ipopt wanders along (reduced Hessian singular, steps of norm 1-8 that change the objective
//       by 1e-6): the hopper standing still took 1465 iterations at sigma = 1 (to Ipopt's
//       acceptable level only); with the equality each stage's alpha is a smooth sigmoid of its
//       switching function, and the same problem took 140, 23, 56, 56, 13, 17 iterations for
//       sigma = 1 .. 1e-5 (bench/README.md, "Hopper over three holes").
//   Penalty (elastic): step k solves
//       min f(x) + rho_k sum_j G_j(x) H_j(x)   s.t. the same, without the rows G_j H_j <= sigma_k,
//   with sigma_{k+1} = kappa sigma_k, sigma_0 given, rho_k = 1 / sigma_k (a sigma_k within 1e-12
//   relative of a power of ten is rounded to it, so that decades are exact: under the smoothing
//   the residual is sigma_k itself).
//   l-infinity elastic steering (options.elastic_infinity, with Scholtes or Smoothing; NOSBENCH,
//   Nurkanovic, Pozharskiy, Diehl 2024, section 3.3 and Table 1, "ELL_INF"; mpcc_robustness.md
//   R3): ONE slack variable s in [0, elastic_slack_max] replaces sigma_k in every
//   inequality-relaxed pair, and the objective pays for it:
//       min f(x) + s / sigma_k   s.t. the same rows, G_j H_j <= s (not smoothed), G_j H_j = sigma_k
//                                (smoothed pairs, unchanged)
//   A step can then always loosen its pairs (at a price that grows tenfold per decade of sigma)
//   instead of failing when the warm start sits in a wrong branch; an exact penalty: for 1 /
//   sigma_k above the relaxation rows' multiplier sum the minimiser has s = 0 (the products are
//   then exactly complementary, not <= sigma_k). The slack is warm-started with the iterate.
//
// A side that is a single variable with a lower bound >= 0 needs no row for its sign (the bound
// already says it); every other side gets the linear row side(x) >= 0 (identical sides share one
// row: cross-complementarity sums repeat, and duplicate rows would make the constraint Jacobian
// rank deficient for no reason). The relaxation rows and the penalty have exact derivatives from
// the affine sides: d(G H)/dx = G a_H + H a_G, d2(G H)/dx2 = a_G a_H' + a_H a_G'.
//
// Row pruning: more generally, a side that the variable bounds alone keep >= 0 gets no row: its
// least value over the bounds by interval arithmetic, b + sum_i a_i (a_i > 0 ? x_lower_i :
// x_upper_i) (finite bounds where needed), is >= 0 (up to 8 eps of rounding). The single
// variable with lower bound >= 0 is the simplest case; FESD's sums of step functions alpha in
// [0, 1], n_s - sum alpha and 1 - alpha are others. With bound_relax_factor = 0 Ipopt keeps the
// bounds, hence these sides, exactly. MpccSolution::sign_rows and relaxed_rows count the rows.
//
// Each step starts from the last successful step's primal-dual solution (warm start, below). The
// homotopy stops with converged == true at the first SUCCESSFUL step whose complementarity
// residual, the largest product of a pair max_j |G_j(x) H_j(x)|, is <= complementarity_tolerance
// (then polished, below; with complementarity_refinement it may go on past that step, without
// polishing, keeping only steps that lower the residual and stay feasible);
// otherwise (steps exhausted, the first step failing, or a step failing after its retries) with
// converged == false and the last successful iterate (NOSNOC: return the last successful iterate,
// mpcc_robustness.md R2), or the last iterate when no step succeeded.
//
// Polishing (options.polish; mpcc_robustness.md R5, the "cheap version without an LPEC" of
// NOSBENCH 5.5 and MPECopt's branch NLP): a relaxed solution with residual 1e-9 can still be
// inaccurate (G = 1e-5 against H = 1e-4 meets the tolerance). After a successful step whose
// residual is <= polish_below, and after the last successful step of the homotopy in any case,
// the solver guesses the active set and solves the branch NLP (BNLP) from the step's primal-dual
// solution: every pair j gets ONE side set to zero and the other kept >= 0, no products:
//   Branch rule: the side Z with the smaller |Z(x)| / ||a_Z||_2, the Euclidean distance from the
//   step's x to the hyperplane Z = 0 (invariant to scaling a side; ties: the left side G). A pair
//   with both distances below sqrt(complementarity_tolerance) is counted as biactive, and gets
//   the same rule: its smaller side is zeroed and the other kept >= 0, the larger of the two
//   branch NLPs (the tightened NLP, both zero, removes freedom the solution may need).
//   Fallback (polish_fallback, off by default, measurements there; NOSBENCH 5.5's "move biactive
//   pairs into single branches"): for a biactive pair the rule is a guess, and a wrong one can make
//   the branch NLP infeasible (FESD time-freezing, an impact's frozen phase: the gap drifted to
//   -1e-5 under the relaxation, its multiplier lambda_n and the step function sum(alpha) both ~1e-5;
//   the rule zeroes lambda_n, which forces gap >= 0, infeasible; the right branch zeroes alpha, the
//   clock stands still). When the first attempt fails (its branch infeasible by its bounds, Ipopt's
//   failure, or the acceptance checks below), attempt 1 flips ALL biactive pairs to their other
//   side; when that fails too and there are 2..polish_single_flip_max_biactive biactive pairs,
//   attempts 2, 3, ... flip ONE biactive pair each against the first guess, largest first (by the
//   larger of the pair's two distances), at most polish_single_flips of them. Each attempt is a
//   polish step of its own (MpccHomotopyStep::polish_attempt), from the same step solution, with its
//   own polish_max_iter. (Mixed flips beyond these are not tried: 2^|biactive| branches; the single
//   flips cover the case of one wrong guess among several right ones, the flip of all the case of
//   one physical mechanism, e.g. an impact, wrongly guessed in all its pairs.) When every attempt
//   fails, the homotopy goes on and the next step guesses again from a better resolved iterate.
//   A zero side becomes BOUNDS where it can: a side whose least value over the variable bounds is
//   0 (interval arithmetic, as above: a single variable with lower bound 0, 1 - alpha, sums of
//   alpha or of 1 - alpha over alpha in [0, 1]) is zero exactly when each of its variables sits at
//   the bound attaining that least value: those variables are fixed there (x_l = x_u; Ipopt's
//   default fixed_variable_treatment = make_parameter removes them), and a side with one
//   variable, a x_i + b, fixes x_i = -b / a. Any other zero side gets the equality row Z(x) = 0.
//   The other side keeps a >= 0 row unless the branch's bounds keep it >= 0 (row pruning). Fixings
//   that contradict each other or the bounds fail the polish without an Ipopt solve.
// A polish attempt succeeds when Ipopt's result is accepted as a step's would be (accept_acceptable,
// within polish_max_iter iterations), its violation of the original constraints is <=
// polish_feasibility_tolerance, the ORIGINAL pairs' residual is <= complementarity_tolerance
// (zero sides held by fixed variables are exactly 0), and its objective exceeds the step's by
// no more than the relaxation explains (polish_objective_increase). Then the homotopy stops there, converged, with the polished point: its x, the
// multipliers of the original rows (the branch rows' multipliers are dropped) and the bound
// multipliers as Ipopt reports them, except for fixed variables, for which Ipopt 3.11 reports
// zeros: there z_L - z_U is the gradient of the branch NLP's Lagrangian, grad f + J' lambda with
// the branch rows included, split into its positive and negative parts (so a variable the branch
// fixed carries its pair's multiplier in z_L or z_U). A failed polish (all its attempts failed)
// is recorded and the homotopy goes on from the step's own solution, which remains the result if
// no later polish succeeds.
#pragma once

#include <saltus/timefreezing/mpcc/mpcc.hpp>

#include <Eigen/Core>

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

/// Settings of solve_mpcc. Defaults follow NOSNOC's current defaults (nosnoc_facts.md section 3)
/// where the brief and the evidence agree; deviations are explained per field.
struct MpccSolverOptions {
  enum class Relaxation {
    Scholtes,   ///< G_j H_j <= sigma_k as constraint rows (the most robust in NOSBENCH-S)
    /// G_j H_j = sigma_k for the smoothable pairs, <= sigma_k for the others (top of file). Only
    /// pairs the problem marks smoothable are smoothed: FesdMpcc marks its stage-wise pairs, which
    /// exist for the velocities with velocity_switch_detection = false and for every switching
    /// function with switch_detection = false; with FESD's defaults there are none and Smoothing
    /// is Scholtes (MpccSolution::smoothed_pairs says how many were smoothed).
    Smoothing,
    Penalty     ///< rho_k sum_j G_j H_j in the objective, rho_k = 1 / sigma_k
  };
  Relaxation relaxation = Relaxation::Scholtes;
  /// The l-infinity elastic steering (top of file) of the inequality-relaxed pairs; Scholtes or
  /// Smoothing only (validate() refuses it with Penalty). Off by default: measured on the hopper
  /// in bench/README.md.
  bool elastic_infinity = false;
  /// Upper bound of the elastic slack (> 0 and finite; NOSNOC's s_elastic_max = 10). The slack
  /// starts at min(sigma_0, elastic_slack_max).
  double elastic_slack_max = 10.0;
  /// First relaxation parameter (Penalty: rho_0 = 1 / sigma_0). NOSBENCH 5.4: sigma_0 in [0.1, 10];
  /// a too small sigma_0 loses problems to bad local minima.
  double sigma_0 = 1.0;
  /// sigma_{k+1} = kappa sigma_k, kappa in (0, 1).
  double kappa = 0.1;
  /// Converged when a successful step has max_j |G_j H_j| <= this.
  double complementarity_tolerance = 1e-9;
  /// Refinement past convergence (0: off; else in [0, complementarity_tolerance]). A product
  /// G_j H_j <= 1e-9 still lets both sides be ~3e-5: in a time-freezing simulation the frozen phase
  /// of an impact, where the gap's pair is degenerate (both sides vanish exactly), then lets the
  /// gap drift to -1.6e-5 and the clock creep 5e-6 (Example 3, n_s = 2: that drift was the whole
  /// final error at 112 elements; bench/README.md, "Where Example 3's error came from"). With a
  /// target, a converged
  /// homotopy whose polish did not succeed goes on decreasing sigma while its steps succeed and
  /// their residual shrinks, until the residual is <= this target; the first step that fails (no
  /// retries) or does not lower the residual ends the refinement, and the result is the last
  /// successful step, still converged; so does a step whose constraint violation exceeds the
  /// previous step's (or polish_feasibility_tolerance, whichever is larger). Refinement steps
  /// count against max_homotopy_steps, are listed in `steps` and are not polished; the message
  /// says how many were accepted and why the refinement ended.
  /// So with `polish` on (the default) it only acts where the polish failed: a successful polish
  /// is exactly complementary already. (A user's trial on a frictional landing, every polish
  /// successful: no effect; with polish = false it took the stop error from 4.6e-6 to 1.4e-8.)
  double complementarity_refinement = 0.0;
  /// Number of homotopy steps (sigma values), retries of a step not counted; >= 1.
  int max_homotopy_steps = 30;
  /// A step whose Ipopt solve fails is restarted from the last successful iterate with a slower
  /// decrease, kappa <- sqrt(kappa) (kept for the rest of the homotopy: the failure says the path
  /// needs smaller steps; NOSBENCH 5.4 and FESD-J: larger kappa solves more of the hard problems),
  /// at most this many times per step; >= 0. The first step has no iterate to restart from: its
  /// failure ends the homotopy.
  int max_step_retries = 3;
  /// >= 0; 0: off (the slow-down of a retry is kept for the rest of the homotopy). Otherwise a
  /// successful step (a first attempt, not a retry) that took at most this many Ipopt iterations
  /// undoes one retry's slow-down:
  /// kappa <- max(kappa^2, this->kappa) for the next step. Why: a retry's sqrt compounds (after
  /// four, kappa = 0.1^(1/16) = 0.87), and past a hard stretch of the path the steps can become
  /// cheap again; measured on the hopper over one hole (bench/README.md) steps of 18-20 iterations
  /// crept down by 3.5 % each. (NOSNOC issue 104 proposes the opposite move, a non-monotone
  /// sigma on failure; this is the same bookkeeping on success.)
  int kappa_recovery_iterations = 0;

  // ---- Ipopt, per step
  /// Ipopt `tol` (> 0). For OCPs 1e-8 with the Penalty relaxation is much faster (point-mass
  /// time-freezing OCP, N = 10, Scholtes: 1e-10 cycles at mu = 1e-11 for hundreds of iterations,
  /// 6368 iterations in all against 1976 with 1e-8; Penalty with 1e-8: 422); the FESD simulations
  /// need 1e-10 (with 1e-8 the guiding example's homotopy fails in one control interval), so the
  /// default stays 1e-10 (solve_time_freezing_ocp's docstring).
  double tol = 1e-10;
  int max_iter = 3000;      ///< Ipopt `max_iter` per step (>= 0)
  int print_level = 0;      ///< Ipopt `print_level` (0..12); 0: no Ipopt output at all
  std::string mu_strategy = "adaptive";  ///< Ipopt `mu_strategy`
  /// Ipopt `mu_oracle`; "quality-function" is what NOSNOC, MPECopt and the NOSBENCH runs use
  /// (mpcc_robustness.md 3.1). With warm-started duals the adaptive oracle starts from the small
  /// complementarity of the previous solution instead of a large barrier parameter.
  std::string mu_oracle = "quality-function";
  /// A step also counts as successful when Ipopt stops at Solved_To_Acceptable_Level (NOSBENCH
  /// scores these as solved, mpcc_robustness.md R2), or at Search_Direction_Becomes_Too_Small
  /// with the original constraint violation <= small_step_feasibility_tolerance (ditto).
  bool accept_acceptable = true;
  double small_step_feasibility_tolerance = 1e-8;
  /// Ipopt `bound_relax_factor`. 0: bounds (among them the sign bounds G, H >= 0 of single-variable
  /// sides) hold exactly, so products measure complementarity; Ipopt's 1e-8 would let both sides
  /// of a pair go slightly negative (NOSNOC, MPECopt and NOSBENCH all use 0).
  double bound_relax_factor = 0.0;

  /// Warm start every step but the first from the previous successful step's primal AND dual
  /// solution (x, constraint multipliers including the relaxation rows, z_L, z_U), with Ipopt's
  /// warm_start_init_point = yes. false: each step starts from the previous x only, with Ipopt's
  /// own initialisation of the multipliers and its default push away from the bounds (NOSNOC's
  /// default, warm_start_duals = false).
  bool warm_start = true;
  /// Only with warm_start = false (no effect otherwise): every homotopy solve with sigma <= this,
  /// a step or a retry, starts from the previous successful step's primal-dual solution as with
  /// warm_start = true; the solves above it, and every polish, start from x alone (>= 0; 0:
  /// never). Why: a primal-only start lets Ipopt push
  /// the iterate 1e-2 from its bounds and initialise the multipliers afresh, which is what carries
  /// the hopper's homotopy past its wall near 1e-4 (bench/README.md, "Warm starts"), but once the
  /// contact modes are settled every step repeats that excursion. Measured on the one-hole bed
  /// (bench/README.md, "Warm starts below a sigma"): with 1e-6 the five steps 1e-6 .. 1e-10 took
  /// 576 Ipopt iterations instead of 1,950 (the homotopy 3,999 instead of 5,373), converged to
  /// another local solution (objective 20.36 against 20.66); with 1e-5 the step at 1e-5 failed.
  /// Not used by the scenes' settings (that page says why).
  double warm_start_below = 0.0;
  /// Ipopt's warm_start_bound_push, warm_start_bound_frac, warm_start_slack_bound_push and
  /// warm_start_slack_bound_frac (> 0, frac capped at 0.5). Small: the previous solution sits on
  /// its active bounds and Ipopt's default (1e-3) would push it away from them, undoing most of
  /// the warm start (mpcc_robustness.md 3.1 suggests 1e-6..1e-9). Measured on the 10-step
  /// Scholtes homotopy of tests/test_mpcc_solver.cpp (SmallMpcc), total Ipopt iterations with
  /// mult push 1e-6: bound push 1e-3 -> 36, 1e-6 -> 26, 1e-9 -> 24; primal-only starts: 72.
  double warm_start_bound_push = 1e-9;
  /// Ipopt's warm_start_mult_bound_push (> 0): the least value a warm-started bound multiplier is
  /// raised to. Small for the same reason: the inactive bounds' multipliers are ~0 at a solution
  /// (same measurement, bound push 1e-9: mult push 1e-3 -> 44 iterations, 1e-6 and 1e-9 -> 24;
  /// 1e-6 keeps a margin from zero for the multipliers Ipopt divides by).
  double warm_start_mult_bound_push = 1e-6;
  /// Ipopt's `mumps_mem_percent` (>= 0): the extra MUMPS workspace, in percent of its estimate,
  /// allocated for every factorisation (Ipopt raises it and factorises again when MUMPS reports it
  /// too small). Ipopt's default 1000 is kept. Measured (bench/README.md, "Where a simulation's
  /// time goes"; `fesd_accuracy ... --ipopt mumps_mem_percent=100`): 100 makes the small FESD
  /// solves 25-35 % faster (the frictional landing 6.1 -> 4.6 s, Example 3 with n_s = 3 at 112
  /// elements 13.0 -> 8.5 s, the same iteration counts and errors; with 1000 a profile shows page
  /// faults in MUMPS' workspace), but on ill-conditioned homotopies the iterates differ (Example 3,
  /// n_s = 2, 1,120 elements: final error 1.07e-7 and the lift-off read 6e-3 late, against 7.65e-9
  /// and 7.8e-6 with 1000; the plank-box OCP's fourth step: 1,123 iterations against 500; 20
  /// changes them even on the landing), so it is not the default. An entry "mumps_mem_percent" in
  /// ipopt_options overrides this field (they are applied last).
  int mumps_mem_percent = 1000;

  // ---- Polishing by a branch NLP (top of this file)
  /// Try the branch NLP after the successful steps with residual <= polish_below and after the
  /// last successful step; stop at the first polish that succeeds. (Not saltus::polish() of
  /// hybrid/reference/resimulation.hpp, which re-simulates an imported reference.)
  bool polish = true;
  /// >= 0. Default 0: polish only after the homotopy's last successful step. Early polishing
  /// (1e-6) saves steps on small problems (tests: SmallMpcc 22 instead of 24 iterations) but on
  /// the chained FESD simulation of time-freezing Example 3 (4 elements, 2 Radau stages) a
  /// polish at sigma = 1e-6 guesses branches the homotopy has not resolved yet; the exact but
  /// different interval end states then led a later interval to a worse local solution and an
  /// infeasible one after it (not converged, 55000 Ipopt iterations against 4255).
  double polish_below = 0.0;
  /// The polished point's largest violation of the original constraints (bounds, g, the sides'
  /// signs) for the polish to count (>= 0).
  double polish_feasibility_tolerance = 1e-8;
  /// Ipopt `max_iter` of a polish (>= 0). From the warm start, a right guess converges in a few
  /// iterations; a wrong one can wander for thousands (FESD time-freezing, Example 3: 3000).
  int polish_max_iter = 100;
  /// The polish is rejected when its objective exceeds the step's by more than
  /// 2 sum_j w_j |G_j H_j| + polish_objective_increase * max(1, |f_step|) (>= 0), w_j the pair's
  /// weight in the step's Lagrangian (Scholtes: the relaxation row's multiplier; Penalty: rho):
  /// the relaxed optimum lies about sum_j w_j |G_j H_j| below the MPCC's, more means the branch
  /// NLP found another, worse local solution (a wrong or premature guess of the branch).
  double polish_objective_increase = 1e-4;
  /// When a polish's first guess fails, try again with the biactive pairs on their other side
  /// (all of them, then single ones; top of this file). false: one attempt per polish.
  /// Off by default: on the chained FESD simulations (time-freezing Example 3 and the frictional
  /// landing, one MPCC per control interval) the fallback does rescue the failed polishes, but
  /// the exactly complementary interval end states (e.g. the gap exactly 0 through a frozen
  /// phase) then lead a later interval to a worse local solution: Example 3 (4 elements, 2
  /// stages) final error 1.4e-4 -> 8.2e-4 and not converged, 5567 -> 37729 Ipopt iterations;
  /// 8 elements 1.41e-5 -> 1.64e-5 (2885 -> 9419 iterations); landing 2.0e-6 -> 7.8e-6 (3535 ->
  /// 7343); 3 stages unchanged (no biactive pair in its failed polish).
  bool polish_fallback = false;
  /// Attempts that flip ONE biactive pair (largest first) after the flip of all of them failed
  /// (>= 0; 0: stop after the flip of all). Each costs up to polish_max_iter iterations.
  int polish_single_flips = 4;
  /// Single flips only when the polish has at most this many biactive pairs (>= 0): with many,
  /// one flip is unlikely to be the missing change and the cap would cover few of them.
  int polish_single_flip_max_biactive = 16;

  /// Extra Ipopt options, applied last. An option Ipopt rejects throws InvalidArgument.
  std::vector<IpoptOption> ipopt_options;

  /// One line per Ipopt solve (homotopy step or retry) when not null: step, sigma (or rho),
  /// complementarity residual, objective, constraint violation, Ipopt iterations and status,
  /// seconds, then the elastic slack ("slack ...", with elastic_infinity) and, for a failed step,
  /// the row its iterate violates most ("worst: ...", MpccHomotopyStep::worst_violation); per
  /// polish attempt also which attempt ("attempt 0 [first guess]", "attempt 1 [biactive flipped
  /// (3)]", "attempt 2 [flipped <pair name>]"), the branch, why it failed and, when its violation
  /// exceeds polish_feasibility_tolerance, its worst row ("worst: ..."). Not owned; must outlive
  /// the call.
  std::ostream* progress = nullptr;

  /// Throws InvalidArgument naming the first field out of its domain.
  void validate() const;
};

/// A starting point other than problem.initial_point(): x (size n), and optionally the
/// multipliers of a previous solution of the same problem (sizes m, n, n; all three or none).
/// With multipliers (and options.warm_start, or options.sigma_0 <= options.warm_start_below) the
/// first step is warm-started too; the first
/// step's relaxation rows start with zero multipliers.
struct MpccStart {
  Eigen::VectorXd x;
  Eigen::VectorXd constraint_multipliers;   ///< empty or size m
  Eigen::VectorXd bound_multipliers_lower;  ///< empty or size n (>= 0)
  Eigen::VectorXd bound_multipliers_upper;  ///< empty or size n (>= 0)
};

/// One Ipopt solve of the homotopy (a step, or a retry of one), or a polish (branch NLP).
struct MpccHomotopyStep {
  int index = 0;    ///< homotopy step k (0-based); retries of a step share its index; a polish
                    ///< has the index of the step it started from
  int retry = 0;    ///< 0 for the first attempt of the step, 1.. for its retries; 0 for a polish
  double sigma = 0.0;  ///< relaxation parameter of the step (Penalty: rho = 1 / sigma); a
                       ///< polish: that of the step it started from
  bool polish = false;  ///< a polish (branch NLP), not a relaxed step
  int left_zero = 0;    ///< polish: pairs whose branch sets the left side G_j = 0
  int right_zero = 0;   ///< polish: pairs whose branch sets the right side H_j = 0
  int biactive = 0;     ///< polish: pairs with both sides within sqrt(complementarity_tolerance)
  int by_trend = 0;     ///< polish: pairs whose branch the trend decided against the distances
  /// polish: 0 the first guess; 1 the biactive pairs flipped; 2, 3, ... one biactive pair
  /// flipped (the fallback, top of this file).
  int polish_attempt = 0;
  int flipped = 0;        ///< polish: pairs whose branch differs from the first guess
  int flipped_pair = -1;  ///< polish attempt >= 2: the pair flipped (index into the pairs)
  std::string note;     ///< polish: why it failed ("" when it succeeded)
  double complementarity = 0.0;       ///< max_j |G_j(x) H_j(x)| at the step's final iterate
  double objective = 0.0;             ///< original f at the step's final iterate (no penalty)
  /// The l-infinity slack s at the step's final iterate (its starting value when Ipopt returned
  /// no iterate; 0 without elastic_infinity).
  double elastic_slack = 0.0;
  double constraint_violation = 0.0;  ///< of the original MPCC (MpccSolution::constraint_violation)
  /// The bound, row or complementarity side attaining constraint_violation, by the Mpcc's names
  /// (Mpcc::variable_name, constraint_name, the pair's name; FesdMpcc's rows read e.g.
  /// "stage dynamics[k,j,r][i]": control interval k, finite element j, stage r, state component i,
  /// all from 0); set for every step, also a converged one whose violation is at rounding level;
  /// "" only when nothing is violated at all. The progress line prints it for failed steps and
  /// for polish attempts whose violation exceeds polish_feasibility_tolerance.
  std::string worst_violation;
  int ipopt_iterations = 0;
  std::string ipopt_status;  ///< Ipopt's ApplicationReturnStatus by name, e.g. "Solve_Succeeded"
  /// The step counts as successful (accept_acceptable); a polish: it was accepted (Ipopt, the
  /// violation and the residual, top of this file).
  bool ipopt_succeeded = false;
  double seconds = 0.0;          ///< wall time of the step
};

/// Result of solve_mpcc. x and the multipliers are those of the successful polish, or else of the
/// last successful step (or of the last step when none succeeded; or the starting point with zero
/// multipliers when Ipopt returned no iterate at all). Multipliers use Ipopt's sign convention, at a solution of the
/// last relaxed problem: grad f + J_g' lambda + (J of the sign and relaxation rows)' mu - z_L + z_U
/// = 0 with z_L, z_U >= 0; only lambda (the original rows) is returned.
struct MpccSolution {
  bool converged = false;  ///< a successful step had complementarity <= complementarity_tolerance
  std::string message;     ///< why the homotopy stopped
  Eigen::VectorXd x;                        ///< size n
  Eigen::VectorXd constraint_multipliers;   ///< size m: the ORIGINAL constraints only
  Eigen::VectorXd bound_multipliers_lower;  ///< size n
  Eigen::VectorXd bound_multipliers_upper;  ///< size n
  /// The problem's own f(x), without the relaxation's penalty. For FesdMpcc that is the OCP's cost
  /// PLUS its regularisation terms (heuristic step equilibration rho_h sum (h - h0)^2, speed of
  /// time rho_s sum (s - 1)^2, contact-side selection rho_c sum alpha_gap): the running cost alone is the cost state L at the final point,
  /// points.back().y[cost_index], plus any terminal cost.
  double objective = 0.0;
  double complementarity = 0.0;             ///< max_j |G_j(x) H_j(x)|, 0 without pairs
  /// Largest violation of the original MPCC's constraints at x: of x_lower <= x <= x_upper,
  /// g_lower <= g(x) <= g_upper and of the sides' signs G_j, H_j >= 0 (the relaxation
  /// G_j H_j <= sigma is not part of it; the products are in `complementarity`).
  double constraint_violation = 0.0;
  int ipopt_iterations = 0;  ///< total over all steps and retries
  double seconds = 0.0;      ///< wall time of the whole solve
  std::vector<MpccHomotopyStep> steps;  ///< every Ipopt solve, in order
  std::string worst_pair;  ///< name of the pair with the largest |G_j H_j| at x ("" without pairs or when every product is 0)
  /// Pairs held on G_j H_j = sigma (Relaxation::Smoothing and marked smoothable; 0 otherwise).
  int smoothed_pairs = 0;
  bool polished = false;   ///< x is a polish's (branch NLP) solution
  /// Size of the relaxed NLP: rows m + sign_rows (+ one relaxation row per pair, Scholtes and
  /// Smoothing; none under Penalty). With elastic_infinity the relaxed NLP also has one more
  /// variable, the slack.
  int relaxed_rows = 0;
  int elastic_pairs = 0;  ///< pairs whose relaxation holds the l-infinity slack (elastic_infinity)
  int sign_rows = 0;  ///< rows side(x) >= 0 (after pruning and merging identical sides)
};

/// Solves the MPCC by the homotopy described at the top of this file, from
/// problem.initial_point().
/// @throws InvalidArgument when the problem statement is inconsistent (sizes, bounds with
///   lower > upper or NaN, a non-finite initial point, a structure index out of range, a Hessian
///   entry above the diagonal, a pair side with a variable out of range, repeated or without
///   terms, a non-finite coefficient), the options are invalid, or Ipopt rejects an option or
///   the problem (Invalid_Option, Not_Enough_Degrees_Of_Freedom, Invalid_Problem_Definition).
/// @throws NumericalFailure on Ipopt's internal errors (Unrecoverable_Exception, Internal_Error,
///   Insufficient_Memory, NonIpopt_Exception_Thrown), naming the status and Ipopt's message.
/// Failures of a step (infeasibility, iteration limit, restoration failure, NaN from the
/// problem's functions, which Ipopt handles by cutting the step) are reported, not thrown.
/// Exceptions thrown by the problem's own functions propagate.
MpccSolution solve_mpcc(const Mpcc& problem, const MpccSolverOptions& options = {});

/// The same from a given starting point (and optionally multipliers); throws InvalidArgument
/// also when the start's sizes do not match or it is not finite.
MpccSolution solve_mpcc(const Mpcc& problem, const MpccStart& start, const MpccSolverOptions& options = {});

/// Output of Ipopt's derivative checker (check_derivatives).
struct DerivativeCheckReport {
  int errors = 0;            ///< entries Ipopt flagged ("Derivative checker detected N error(s).")
  std::string output;        ///< Ipopt's checker output: the flagged entries and the verdict
  std::string ipopt_status;  ///< status of the zero-iteration Ipopt run that hosted the check
};

/// Runs Ipopt's own derivative checker (derivative_test = second-order, forward differences) on
/// the Scholtes-relaxed NLP at exactly x (point_perturbation_radius = 0: Ipopt would otherwise
/// check at a random point within 10 of x): gradient of f, Jacobian of g and of the sign and
/// relaxation rows, Hessians of f, of every g_j and of every relaxation row. An entry is flagged
/// when |approx - exact| / max(|approx|, 1) >= tolerance; `perturbation` is relative,
/// perturbation * max(1, |x_i|). Nothing is printed.
/// @pre x has size n, is finite and within the bounds; perturbation > 0; tolerance > 0.
/// @throws InvalidArgument as solve_mpcc for the problem statement, and for x or the numbers.
/// @throws NumericalFailure when Ipopt's output holds no verdict (the check could not run, e.g.
///   a function could not be evaluated at x), with Ipopt's status and output.
/// With elastic_slack, the NLP checked is the l-infinity elastic one (every pair's row
/// G_j H_j - s <= 0, the objective f + s; the slack at 0.5 in [0, 10]), sigma = 1.
DerivativeCheckReport check_derivatives(const Mpcc& problem, const Eigen::VectorXd& x, double perturbation = 1e-7,
                                        double tolerance = 1e-4, bool elastic_slack = false);

/// Throws InvalidArgument naming the first inconsistency of the problem statement (see
/// solve_mpcc). Evaluates the bounds, the initial point and the structures, no function.
void validate_problem(const Mpcc& problem);

}  // namespace saltus::timefreezing
