// Private: a reformulation of an Mpcc as an NLP over the same n variables, as data. The relaxed NLP
// of a homotopy step (relaxation.hpp) and the branch NLP of a polish (branch.hpp) are two of them;
// the one Ipopt adapter (ipopt_adapter.hpp) solves any.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace saltus::timefreezing::detail {

/// The NLP, over the Mpcc's x (an MpccLayout's sides and merged structures):
///   min  f(x) + [penalty] (1 / penalty_sigma) sum_j G_j(x) H_j(x)
///   s.t. g_lower <= g(x) <= g_upper                               rows [0, m)
///        affine_lower[r] <= side_{affine_side[r]}(x) <= affine_upper[r]
///                                                               rows [m, m + n_affine)
///        product_lower[j] <= G_j(x) H_j(x) <= product_upper[j]   rows [m + n_affine, m_total),
///                                                               one per pair, when product_rows
///        x_lower <= x <= x_upper.
/// Which rows and terms exist (affine_side, product_rows, penalty) is the NLP's structure, fixed
/// once an adapter is built on it; the bounds and penalty_sigma are its parameters and may change
/// between solves (a homotopy step's sigma). A bound of +-infinity is none (beyond Ipopt's
/// nlp_lower_bound_inf and nlp_upper_bound_inf, -+1e19).
struct Reformulation {
  Eigen::VectorXd x_lower, x_upper;  ///< size n; x_lower[i] == x_upper[i] fixes x_i
  std::vector<int> affine_side;      ///< per affine row: the side (2j: G_j, 2j + 1: H_j) it holds
  std::vector<double> affine_lower, affine_upper;
  bool product_rows = false;
  std::vector<double> product_lower, product_upper;  ///< per pair, with product_rows
  bool penalty = false;                              ///< the objective's penalty term, rho = 1 / penalty_sigma
  double penalty_sigma = 1.0;
  /// Complete the bound multipliers of fixed variables from the Lagrangian's gradient (Ipopt 3.11
  /// reports zeros for them; ipopt_adapter.hpp). Only without product rows and penalty.
  bool complete_fixed_multipliers = false;

  int affine_row_count() const { return static_cast<int>(affine_side.size()); }
  /// m + affine rows + product rows, for pair_count pairs.
  int row_count(int m, int pair_count) const { return m + affine_row_count() + (product_rows ? pair_count : 0); }
  /// The first product row (pair j's row is this + j).
  int first_product_row(int m) const { return m + affine_row_count(); }
};

}  // namespace saltus::timefreezing::detail
