// Private: what every reformulation of one Mpcc shares, read from it once: its bounds, its
// complementarity sides in compressed rows, and its Jacobian and Hessian structures merged into
// unique positions (with the positions of the pairs' product Hessians). Only the sources of
// saltus_timefreezing include this header.
#pragma once

#include <Eigen/Core>
#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing::detail {

/// Interval arithmetic on an affine expression c + sum_t a_t x_{var_t} over the box
/// x_lower <= x <= x_upper: its least value, c + sum_t a_t (a_t > 0 ? x_lower : x_upper) (terms
/// with a_t = 0 contribute nothing), -infinity when a needed bound is infinite. `magnitude`
/// (optional) receives |c| + sum_t |a_t b_t| over the same bounds b_t, the scale of the rounding
/// error of the sum.
double interval_lower(const int* var, const double* coef, int count, double constant, const Eigen::VectorXd& x_lower,
                      const Eigen::VectorXd& x_upper, double* magnitude = nullptr);

/// The rounding allowance of interval_lower: 8 eps * magnitude.
double interval_slack(double magnitude);

/// A side's identity for merging identical rows: its (variable, coefficient) terms sorted by
/// variable, and its constant.
using SideKey = std::pair<std::vector<std::pair<int, double>>, double>;

/// The layout of one Mpcc (sizes n, m, n_pairs). Sides are numbered s = 2j (G_j) and 2j + 1 (H_j);
/// their terms are sorted by variable. Merged structures: the problem's Jacobian (Hessian) entries
/// may repeat (mpcc.hpp), and a pair's Hessian a_G a_H' + a_H a_G' lands on entries of f and g
/// too. Ipopt 3.11's triplet matrices add repeated entries (IpGenTMatrix.hpp: "If nonzero elements
/// are listed more than once, their values are added"), but the TNLP documentation does not
/// promise it and its finite-difference Jacobian refuses them (IpTNLPAdapter.cpp: "multiple
/// occurances of the same position"); unique positions take the question off the table, at the
/// cost of one scatter per evaluation through the precomputed maps.
class MpccLayout {
 public:
  /// The problem must have passed validate_problem and outlive this object.
  explicit MpccLayout(const Mpcc& problem);

  const Mpcc& problem() const { return problem_; }
  int variable_count() const { return n_; }
  int constraint_count() const { return m_; }
  int pair_count() const { return n_pairs_; }
  const Eigen::VectorXd& x_lower() const { return x_lower_; }
  const Eigen::VectorXd& x_upper() const { return x_upper_; }
  const Eigen::VectorXd& g_lower() const { return g_lower_; }
  const Eigen::VectorXd& g_upper() const { return g_upper_; }

  // ---- Sides: side s has the terms [side_begin(s), side_end(s)).
  int side_begin(int s) const { return side_ptr_[s]; }
  int side_end(int s) const { return side_ptr_[s + 1]; }
  int term_variable(int t) const { return side_var_[t]; }
  double term_coefficient(int t) const { return side_coef_[t]; }
  double side_constant(int s) const { return side_constant_[s]; }
  double side_norm(int s) const { return side_norm_[s]; }  ///< ||a||_2
  /// The side is the single variable x_i (coefficient 1, constant 0); returns i or -1.
  int side_single_variable(int s) const;
  SideKey side_key(int s) const;
  /// Value of side s (2j: G_j, 2j+1: H_j) at x.
  double side_value(int s, const double* x) const {
    double v = side_constant_[s];
    for (int t = side_ptr_[s]; t < side_ptr_[s + 1]; ++t) v += side_coef_[t] * x[side_var_[t]];
    return v;
  }
  double side_value(int s, const Eigen::Ref<const Eigen::VectorXd>& x) const { return side_value(s, x.data()); }
  /// interval_lower of side s over the box [x_lower, x_upper].
  double side_lower_bound(int s, const Eigen::VectorXd& x_lower, const Eigen::VectorXd& x_upper,
                          double* magnitude = nullptr) const;
  /// "left side of <pair name>" or "right side of <pair name>".
  std::string side_name(int s) const;

  // ---- Merged structures (ordered by row, then column).
  /// The problem's Jacobian: unique positions; entry e of jacobian_values goes to
  /// jacobian_map()[e].
  const std::vector<int>& jacobian_rows() const { return jac_row_; }
  const std::vector<int>& jacobian_cols() const { return jac_col_; }
  const std::vector<int>& jacobian_map() const { return jac_map_; }
  /// The Lagrangian's Hessian, lower triangle: the problem's entries (hessian_map) and every
  /// pair's a_G a_H' + a_H a_G' (position, coefficient) in [pair_hessian_begin(j),
  /// pair_hessian_begin(j + 1)).
  const std::vector<int>& hessian_rows() const { return hess_row_; }
  const std::vector<int>& hessian_cols() const { return hess_col_; }
  const std::vector<int>& hessian_map() const { return hess_map_; }
  int pair_hessian_begin(int j) const { return pair_hess_ptr_[j]; }
  int pair_hessian_position(int t) const { return pair_hess_pos_[t]; }
  double pair_hessian_coefficient(int t) const { return pair_hess_coef_[t]; }

  // ---- Measures of the original MPCC.
  /// max_j |G_j(x) H_j(x)| and the pair attaining it (-1 without pairs; a NaN product is the worst).
  double complementarity(const Eigen::Ref<const Eigen::VectorXd>& x, int* worst_pair = nullptr) const;
  /// Largest violation of the original MPCC at x: bounds, g, and the sides' signs; `worst`, when
  /// given, gets the name of the bound, row or side attaining it ("" when nothing is violated).
  /// Uses an internal buffer: not for concurrent calls.
  double constraint_violation(const Eigen::Ref<const Eigen::VectorXd>& x, std::string* worst = nullptr);

 private:
  void read_sides();
  void merge_jacobian();
  void merge_hessian();

  const Mpcc& problem_;
  int n_ = 0, m_ = 0, n_pairs_ = 0;
  Eigen::VectorXd x_lower_, x_upper_, g_lower_, g_upper_;
  std::vector<int> side_ptr_, side_var_;
  std::vector<double> side_coef_, side_constant_, side_norm_;
  std::vector<int> jac_row_, jac_col_, jac_map_;
  std::vector<int> hess_row_, hess_col_, hess_map_;
  std::vector<int> pair_hess_ptr_, pair_hess_pos_;
  std::vector<double> pair_hess_coef_;
  Eigen::VectorXd g_buffer_;  ///< constraint_violation's workspace
};

}  // namespace saltus::timefreezing::detail
