// What solve_mpcc (solve.hpp) takes besides the problem and the options, and what it returns: a
// starting point, one record per Ipopt solve, the solution.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace saltus::timefreezing {

/// A starting point other than problem.initial_point(): x (size n), and optionally the
/// multipliers of a previous solution of the same problem (sizes m, n, n; all three or none).
/// With multipliers (and options.warm_start) the first step is warm-started too; the first step's
/// relaxation rows start with zero multipliers.
struct MpccStart {
  Eigen::VectorXd x;
  Eigen::VectorXd constraint_multipliers;   ///< empty or size m
  Eigen::VectorXd bound_multipliers_lower;  ///< empty or size n (>= 0)
  Eigen::VectorXd bound_multipliers_upper;  ///< empty or size n (>= 0)
};

/// One Ipopt solve of the homotopy (a step, or a retry of one), or a polish (branch NLP).
struct MpccHomotopyStep {
  int index = 0;                      ///< homotopy step k (0-based); retries of a step share its index; a polish
                                      ///< has the index of the step it started from
  int retry = 0;                      ///< 0 for the first attempt of the step, 1.. for its retries; 0 for a polish
  double sigma = 0.0;                 ///< relaxation parameter of the step (Penalty: rho = 1 / sigma); a
                                      ///< polish: that of the step it started from
  bool polish = false;                ///< a polish (branch NLP), not a relaxed step
  int left_zero = 0;                  ///< polish: pairs whose branch sets the left side G_j = 0
  int right_zero = 0;                 ///< polish: pairs whose branch sets the right side H_j = 0
  int biactive = 0;                   ///< polish: pairs with both sides within sqrt(complementarity_tolerance)
  int by_trend = 0;                   ///< polish: pairs whose branch the trend decided against the distances
  std::string note;                   ///< polish: why it failed ("" when it succeeded)
  double complementarity = 0.0;       ///< max_j |G_j(x) H_j(x)| at the step's final iterate
  double objective = 0.0;             ///< original f at the step's final iterate (no penalty)
  double constraint_violation = 0.0;  ///< of the original MPCC (MpccSolution::constraint_violation)
  /// The bound, row or complementarity side attaining constraint_violation, by the Mpcc's names
  /// (Mpcc::variable_name, constraint_name, the pair's name; FesdMpcc's rows read e.g.
  /// "stage dynamics[k,j,r][i]": control interval k, finite element j, stage r, state component i,
  /// all from 0); set for every step, also a converged one whose violation is at rounding level;
  /// "" only when nothing is violated at all. The progress line prints it for failed steps and
  /// for polishes whose violation exceeds polish.feasibility_tolerance.
  std::string worst_violation;
  int ipopt_iterations = 0;
  std::string ipopt_status;  ///< Ipopt's ApplicationReturnStatus by name, e.g. "Solve_Succeeded"
  /// The step counts as successful (homotopy.accept_acceptable); a polish: it was accepted (Ipopt,
  /// the violation, the residual and the objective; solve.hpp, "Polishing").
  bool ipopt_succeeded = false;
  double seconds = 0.0;  ///< wall time of the step
};

/// Result of solve_mpcc. x and the multipliers are those of the successful polish, or else of the
/// last successful step (or of the last step when none succeeded; or the starting point with zero
/// multipliers when Ipopt returned no iterate at all). Multipliers use Ipopt's sign convention, at
/// a solution of the last relaxed problem: grad f + J_g' lambda + (J of the sign and relaxation
/// rows)' mu - z_L + z_U = 0 with z_L, z_U >= 0; only lambda (the original rows) is returned.
struct MpccSolution {
  bool converged = false;                   ///< a successful step had complementarity <= complementarity_tolerance
  std::string message;                      ///< why the homotopy stopped
  Eigen::VectorXd x;                        ///< size n
  Eigen::VectorXd constraint_multipliers;   ///< size m: the ORIGINAL constraints only
  Eigen::VectorXd bound_multipliers_lower;  ///< size n
  Eigen::VectorXd bound_multipliers_upper;  ///< size n
  /// The problem's own f(x), without the relaxation's penalty. For FesdMpcc that is the OCP's cost
  /// PLUS its regularisation terms (heuristic step equilibration rho_h sum (h - h0)^2, speed of
  /// time rho_s sum (s - 1)^2, contact-side selection rho_c sum alpha_gap): the running cost alone
  /// is the cost state L at the final point, points.back().y[cost_index], plus any terminal cost.
  double objective = 0.0;
  double complementarity = 0.0;  ///< max_j |G_j(x) H_j(x)|, 0 without pairs
  /// Largest violation of the original MPCC's constraints at x: of x_lower <= x <= x_upper,
  /// g_lower <= g(x) <= g_upper and of the sides' signs G_j, H_j >= 0 (the relaxation
  /// G_j H_j <= sigma is not part of it; the products are in `complementarity`).
  double constraint_violation = 0.0;
  int ipopt_iterations = 0;             ///< total over all steps and retries
  double seconds = 0.0;                 ///< wall time of the whole solve
  std::vector<MpccHomotopyStep> steps;  ///< every Ipopt solve, in order
  /// Name of the pair with the largest |G_j H_j| at x ("" without pairs or when every product is 0).
  std::string worst_pair;
  /// Pairs held on G_j H_j = sigma (Relaxation::Smoothing and marked smoothable; 0 otherwise).
  int smoothed_pairs = 0;
  bool polished = false;  ///< x is a polish's (branch NLP) solution
  /// Size of the relaxed NLP: rows m + sign_rows (+ one relaxation row per pair, Scholtes and
  /// Smoothing; none under Penalty).
  int relaxed_rows = 0;
  int sign_rows = 0;  ///< rows side(x) >= 0 (after pruning and merging identical sides)
};

}  // namespace saltus::timefreezing
