// Private: the one Ipopt adapter of the MPCC solver: a Reformulation (reformulation.hpp) of an
// Mpcc as an Ipopt::TNLP. Only the sources of saltus_timefreezing include this header (it includes
// Ipopt's).
#pragma once

#include <Eigen/Core>
#include <IpTNLP.hpp>
#include <vector>

#include "mpcc_layout.hpp"
#include "reformulation.hpp"

namespace saltus::timefreezing::detail {

/// A primal-dual point of a reformulated NLP: x (size n), the multipliers of all its rows (size
/// m_total) and of the bounds (sizes n, n), in Ipopt's sign convention.
struct PrimalDual {
  Eigen::VectorXd x, lambda, z_lower, z_upper;
};

/// The Reformulation as Ipopt sees it. Rows in the Reformulation's order; the Jacobian's entries:
/// the problem's merged positions (MpccLayout), then the affine rows' constant entries (row by
/// row, each side's terms by variable), then per pair its product row's entries (one per variable
/// of either side, by variable; d(G H)/dx = G a_H + H a_G). The Hessian: the layout's merged
/// lower triangle, the problem's values plus per pair w_j (a_G a_H' + a_H a_G') with w_j the
/// product row's multiplier, or obj_factor / penalty_sigma under the penalty.
/// Every evaluation returns false on a non-finite result: Ipopt then shortens the step (or stops
/// with Invalid_Number_Detected at the starting point) instead of computing with NaN.
/// The evaluation callbacks allocate nothing: every buffer is sized in the constructor.
class ReformulatedNlp : public Ipopt::TNLP {
 public:
  /// `layout` and `nlp` must outlive this object; nlp's structure (affine_side, product_rows, penalty)
  /// must not change after this, its bounds and penalty_sigma may (they are read at each solve).
  ReformulatedNlp(const MpccLayout& layout, const Reformulation& nlp);

  int row_count() const { return m_total_; }

  /// The point of the next solve, without multipliers (Ipopt initialises them) or with them
  /// (sizes row_count(), n, n; used with warm_start_init_point = yes).
  void set_start(const Eigen::VectorXd& x);
  void set_start(const Eigen::VectorXd& x, const Eigen::VectorXd& lambda, const Eigen::VectorXd& z_lower,
                 const Eigen::VectorXd& z_upper);

  /// Filled by finalize_solution; has_result() is false when Ipopt returned no iterate.
  bool has_result() const { return present_; }
  void clear_result() { present_ = false; }
  /// The last result. With complete_fixed_multipliers, the bound multipliers of fixed variables
  /// (x_l = x_u, among them any the problem fixes itself), which Ipopt 3.11 reports as zeros, are
  /// z_L - z_U = grad f + J' lambda there (stationarity), split into positive and negative parts.
  const PrimalDual& result() const { return result_; }

  // ---- Ipopt::TNLP
  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override;
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m, Ipopt::Number* g_l,
                       Ipopt::Number* g_u) override;
  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number* z_L,
                          Ipopt::Number* z_U, Ipopt::Index m, bool init_lambda, Ipopt::Number* lambda) override;
  bool eval_f(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number& obj_value) override;
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number* grad_f) override;
  bool eval_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m, Ipopt::Number* g) override;
  bool eval_jac_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m, Ipopt::Index nele_jac,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override;
  bool eval_h(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number obj_factor, Ipopt::Index m,
              const Ipopt::Number* lambda, bool new_lambda, Ipopt::Index nele_hess, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override;
  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x, const Ipopt::Number* z_L,
                         const Ipopt::Number* z_U, Ipopt::Index m, const Ipopt::Number* g, const Ipopt::Number* lambda,
                         Ipopt::Number obj_value, const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override;

 private:
  void build_jacobian_structure();
  /// Stores Ipopt's arrays (a null multiplier array stores zeros); false when x is null.
  bool store(const double* x, const double* z_L, const double* z_U, const double* lambda);
  /// The fixed variables' bound multipliers of the stored result (complete_fixed_multipliers).
  void complete_fixed_multipliers();

  const MpccLayout& layout_;
  const Reformulation& nlp_;
  int n_ = 0, m_ = 0, n_pairs_ = 0, n_affine_ = 0, m_total_ = 0;

  // Jacobian (class comment): the affine rows' entries from affine_jac_offset_ with constant
  // values, the product rows' from product_jac_offset_, pair j's [pair_jac_ptr_[j],
  // pair_jac_ptr_[j + 1]) of them with the variable's coefficients in G_j and H_j.
  std::vector<int> jac_row_, jac_col_;
  std::vector<double> affine_jac_value_;
  int affine_jac_offset_ = 0, product_jac_offset_ = 0;
  std::vector<int> pair_jac_ptr_;
  std::vector<double> pair_jac_a_g_, pair_jac_a_h_;

  // Workspaces of the callbacks.
  Eigen::VectorXd jac_buffer_, hess_buffer_, zero_multipliers_, gradient_buffer_;

  // Start of the next solve, and the last result.
  PrimalDual start_;
  bool start_has_multipliers_ = false;
  PrimalDual result_;
  bool present_ = false;
};

}  // namespace saltus::timefreezing::detail
