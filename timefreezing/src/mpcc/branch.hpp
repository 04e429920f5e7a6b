// Private: the branch NLP (BNLP) of a polish as a Reformulation (reformulation.hpp): the guess of
// every pair's branch from a relaxed solution, and the NLP with each pair fixed to its branch
// (solve.hpp, "POLISHING").
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ipopt_adapter.hpp"
#include "mpcc_layout.hpp"
#include "reformulation.hpp"
#include "relaxation.hpp"

namespace saltus::timefreezing::detail {

/// A guess of the pairs' branches: zero_side[j] = 0 sets G_j = 0, 1 sets H_j = 0.
struct BranchGuess {
  std::vector<int> zero_side;
  int biactive = 0;  ///< pairs with both distances below the biactive threshold
  int by_trend = 0;  ///< pairs the trend decided against the distances
};

/// The branch rule at x: per pair the side with the smaller |side(x)| / ||a_side||_2 (the
/// Euclidean distance from x to the hyperplane side = 0; ties: G_j). With `previous` (the previous
/// successful step's x, at sigma_previous > sigma; sigma_ratio = sigma / sigma_previous) the trend
/// overrides the distances: when the side the distances pick does not shrink from previous to x
/// (ratio >= sqrt(sigma_ratio)) while the other one does, the other one is zeroed (G = 1e-5
/// holding still against H = 1e-4 falling with sigma is the branch H = 0).
BranchGuess choose_branches(const MpccLayout& layout, const Eigen::Ref<const Eigen::VectorXd>& x,
                            double biactive_threshold, const Eigen::VectorXd* previous, double sigma_ratio);

/// The branch NLP: the original problem with every pair fixed to one branch, over the same n
/// variables:
///   min f(x)  s.t.  g_lower <= g(x) <= g_upper,  x in the branch bounds,
///                   Z_j(x) = 0  for the chosen zero side Z_j of every pair j,
///                   O_j(x) >= 0 for the other side O_j,
/// with no product rows. A zero side becomes bounds when it can: when its interval_lower over the
/// original bounds is 0 (up to rounding), Z_j = 0 holds exactly when every variable of it sits at
/// the bound that attains the minimum, so those variables are fixed there (x_l = x_u; a single
/// variable x_i with lower bound 0, FESD's 1 - alpha and sums of alpha or of 1 - alpha over alpha
/// in [0, 1]); a side with one variable, a x_i + c, fixes x_i = -c / a. Ipopt's default
/// fixed_variable_treatment = make_parameter takes fixed variables out of the problem. Fixings
/// that contradict each other or the bounds make the branch infeasible before any solve (`why`).
/// Every other zero side gets an equality row; an other side gets a >= 0 row unless the branch
/// bounds keep it >= 0 (interval_lower, as the relaxed NLP's sign rows) or it is also a zero side;
/// identical expressions share one row, and a row whose variables are all fixed is checked once
/// here instead of being handed to Ipopt. Affine rows: the equality rows, then the inequality rows.
struct BranchNlp {
  Reformulation nlp;  ///< with complete_fixed_multipliers
  std::string why;    ///< why the branch is infeasible by its bounds ("": it is not)
  int fixed_variables = 0, equality_rows = 0, inequality_rows = 0;
  /// Per equality row: the other sides of the pairs whose zero side it is.
  std::vector<std::vector<int>> equality_row_other_sides;

  bool infeasible() const { return !why.empty(); }
};

BranchNlp make_branch_nlp(const MpccLayout& layout, const std::vector<int>& zero_side);

/// The branch NLP's starting multipliers from a solution `from` of the relaxed NLP at sigma: the
/// problem's rows keep theirs; an equality row Z = 0 starts with the multiplier of Z's sign row
/// plus, per pair with that zero side, the pair's weight times its other side (the relaxed
/// Lagrangian's term w Z O has the gradient w (O a_Z + Z a_O) ~ w O a_Z at Z ~ 0); an inequality
/// row with its sign row's.
Eigen::VectorXd branch_start_multipliers(const BranchNlp& branch, const MpccLayout& layout, const RelaxedNlp& relaxed,
                                         const PrimalDual& from, double sigma);

}  // namespace saltus::timefreezing::detail
