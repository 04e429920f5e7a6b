// The solver of the MPCCs of mpcc.hpp: a homotopy of relaxed (or penalised) NLPs, each solved by
// Ipopt (3.11, MUMPS), as NOSNOC does (NOSBENCH: A. Nurkanović, A. Pozharskiy, M. Diehl, "Solving
// mathematical programs with complementarity constraints arising in nonsmooth optimal control",
// 2024; S. Scholtes, "Convergence properties of a regularization scheme for mathematical programs
// with complementarity constraints", SIAM J. Optim. 11(4):918-936, 2001). Options:
// solver_options.hpp; results: solution.hpp.
//
// RELAXATIONS (MpccSolverOptions::Relaxation; the private strategies of src/mpcc/relaxation.hpp):
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
//       sigma = 1 .. 1e-5 (bench/experiments/README.md, "Hopper over three holes").
//   Penalty (elastic): step k solves
//       min f(x) + rho_k sum_j G_j(x) H_j(x)   s.t. the same, without the rows G_j H_j <= sigma_k,
//   with sigma_{k+1} = kappa sigma_k, sigma_0 given, rho_k = 1 / sigma_k (a sigma_k within 1e-12
//   relative of a power of ten is rounded to it, so that decades are exact: under the smoothing
//   the residual is sigma_k itself).
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
// [0, 1], n_s - sum alpha and 1 - alpha are others. With bound_relax_factor = 0 (the solver's
// Ipopt default) Ipopt keeps the bounds, hence these sides, exactly. MpccSolution::sign_rows and
// relaxed_rows count the rows.
//
// HOMOTOPY. Each step starts from the last successful step's primal-dual solution (warm start,
// MpccSolverOptions::warm_start). The homotopy stops with converged == true at the first
// SUCCESSFUL step whose complementarity residual, the largest product of a pair
// max_j |G_j(x) H_j(x)|, is <= complementarity_tolerance (then polished, below; with
// complementarity_refinement it may go on past that step, without polishing, keeping only steps
// that lower the residual and stay feasible); otherwise (steps exhausted, the first step failing,
// or a step failing after its retries) with converged == false and the last successful iterate (as
// NOSNOC, which returns the last successful iterate), or the last iterate when no step succeeded.
//
// POLISHING (MpccSolverOptions::Polish; the "cheap version without an LPEC" of NOSBENCH section
// 5.5 and the branch NLP of MPECopt: A. Nurkanović, S. Leyffer, "A globally convergent method for
// computing B-stationary points of mathematical programs with equilibrium constraints", 2025): a
// relaxed solution with residual 1e-9 can still be inaccurate (G = 1e-5 against H = 1e-4 meets the
// tolerance). After a successful step whose residual is <= polish.below, and after the last
// successful step of the homotopy in any case, the solver guesses the active set and solves the
// branch NLP (BNLP) from the step's primal-dual solution: every pair j gets ONE side set to zero
// and the other kept >= 0, no products:
//   Branch rule: the side Z with the smaller |Z(x)| / ||a_Z||_2, the Euclidean distance from the
//   step's x to the hyperplane Z = 0 (invariant to scaling a side; ties: the left side G), unless
//   the trend of the previous successful step says otherwise (the side the distances pick does not
//   shrink with sigma while the other does). A pair with both distances below
//   sqrt(complementarity_tolerance) is counted as biactive and gets the same rule (the tightened
//   NLP, both zero, would remove freedom the solution may need). One guess per polish: when it
//   fails, the homotopy goes on and the next step guesses again from a better resolved iterate
//   (flipping the biactive pairs was measured and removed: docs/decisions/mpcc-polish-fallback.md).
//   A zero side becomes BOUNDS where it can: a side whose least value over the variable bounds is
//   0 (interval arithmetic, as above: a single variable with lower bound 0, 1 - alpha, sums of
//   alpha or of 1 - alpha over alpha in [0, 1]) is zero exactly when each of its variables sits at
//   the bound attaining that least value: those variables are fixed there (x_l = x_u; Ipopt's
//   default fixed_variable_treatment = make_parameter removes them), and a side with one
//   variable, a x_i + b, fixes x_i = -b / a. Any other zero side gets the equality row Z(x) = 0.
//   The other side keeps a >= 0 row unless the branch's bounds keep it >= 0 (row pruning). Fixings
//   that contradict each other or the bounds fail the polish without an Ipopt solve.
// A polish succeeds when Ipopt's result is accepted as a step's would be (accept_acceptable,
// within polish.max_iter iterations), its violation of the original constraints is <=
// polish.feasibility_tolerance, the ORIGINAL pairs' residual is <= complementarity_tolerance (zero
// sides held by fixed variables are exactly 0), and its objective exceeds the step's by no more
// than the relaxation explains (polish.objective_increase). Then the homotopy stops there,
// converged, with the polished point: its x, the multipliers of the original rows (the branch
// rows' multipliers are dropped) and the bound multipliers as Ipopt reports them, except for fixed
// variables, for which Ipopt 3.11 reports zeros: there z_L - z_U is the gradient of the branch
// NLP's Lagrangian, grad f + J' lambda with the branch rows included, split into its positive and
// negative parts (so a variable the branch fixed carries its pair's multiplier in z_L or z_U). A
// failed polish is recorded and the homotopy goes on from the step's own solution, which remains
// the result if no later polish succeeds.
#pragma once

#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <saltus/timefreezing/mpcc/solution.hpp>
#include <saltus/timefreezing/mpcc/solver_options.hpp>

namespace saltus::timefreezing {

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

/// Throws InvalidArgument naming the first inconsistency of the problem statement (see
/// solve_mpcc). Evaluates the bounds, the initial point and the structures, no function.
void validate_problem(const Mpcc& problem);

}  // namespace saltus::timefreezing
