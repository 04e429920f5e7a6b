// Private: the relaxed (Scholtes) or penalised NLP of one homotopy step as an Ipopt TNLP. Only
// the sources of saltus_timefreezing include this header (it includes Ipopt's).
#pragma once

#include <saltus/timefreezing/mpcc/mpcc.hpp>

#include <IpTNLP.hpp>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace saltus::timefreezing::detail {

enum class RelaxationKind { Scholtes, Smoothing, Penalty };

/// The primal-dual point Ipopt hands to finalize_solution, copied into buffers sized once (by
/// resize), so that storing it allocates nothing. Shared by RelaxedNlp and BranchNlp.
struct NlpResult {
  Eigen::VectorXd x, lambda, z_lower, z_upper;  ///< sizes n, m (all rows), n, n
  bool present = false;                         ///< Ipopt returned an iterate

  /// Zero buffers for n variables and m rows; no result present.
  void resize(int n, int m);
  /// Copies Ipopt's arrays (a null multiplier array stores zeros) and sets `present`; does
  /// nothing and returns false when x is null (Ipopt returned no iterate).
  bool store(const double* x_in, const double* z_L, const double* z_U, const double* lambda_in);
};

/// Interval arithmetic on an affine expression c + sum_t a_t x_{var_t} over the box
/// x_lower <= x <= x_upper: its least value, c + sum_t a_t (a_t > 0 ? x_lower : x_upper) (terms
/// with a_t = 0 contribute nothing), -infinity when a needed bound is infinite. `magnitude`
/// (optional) receives |c| + sum_t |a_t b_t| over the same bounds b_t, the scale of the rounding
/// error of the sum.
double interval_lower(const int* var, const double* coef, int count, double constant, const Eigen::VectorXd& x_lower,
                      const Eigen::VectorXd& x_upper, double* magnitude = nullptr);

/// The rounding allowance of interval_lower: 8 eps * magnitude.
double interval_slack(double magnitude);

/// The augmented NLP over the same n variables:
///   rows [0, m)                  the problem's constraints g,
///   rows [m, m + n_sign)         side(x) >= 0 for the sides that need a row: not for a side
///                                the variable bounds alone keep >= 0 (interval_lower >= 0, up
///                                to rounding; e.g. a single variable with lower bound >= 0, or
///                                FESD's sums of step functions alpha in [0, 1] and
///                                n_s - sum alpha), and one row per distinct expression,
///   rows [m + n_sign, m_total)   G_j H_j <= sigma (Scholtes; Smoothing: = sigma for the pairs marked
///                                smoothable), one per pair; none under Penalty.
/// The l-infinity elastic mode (`elastic`, Scholtes or Smoothing only; NOSBENCH Table 1, ELL_INF)
/// adds ONE variable, the slack s at Ipopt's index n (after the problem's n), with bounds
/// [0, elastic_slack_max]: the inequality-relaxed rows read G_j H_j - s <= 0 instead of
/// G_j H_j <= sigma, and the objective gains s / sigma (NOSNOC's objective_scaling_direct: the
/// penalty weight 1 / sigma grows along the homotopy). Smoothed rows keep G_j H_j = sigma. The
/// slack enters linearly: its Jacobian entries are -1 and it adds nothing to the Hessian.
/// Structures are merged once, in the constructor: the problem's Jacobian and Hessian entries
/// may repeat (mpcc.hpp), and a pair's Hessian a_G a_H' + a_H a_G' lands on entries of f and g
/// too. Ipopt 3.11's triplet matrices add repeated entries (IpGenTMatrix.hpp: "If nonzero
/// elements are listed more than once, their values are added"), but the TNLP documentation does
/// not promise it and its finite-difference Jacobian refuses them (IpTNLPAdapter.cpp: "multiple
/// occurances of the same position"); unique positions take the question off the table, at the
/// cost of one scatter per evaluation through the precomputed maps.
/// The evaluation callbacks allocate nothing: every buffer is sized here.
class RelaxedNlp : public Ipopt::TNLP {
 public:
  /// The problem must have passed validate_problem and outlive this object.
  RelaxedNlp(const Mpcc& problem, RelaxationKind kind);
  /// With the l-infinity elastic slack (class comment) in [0, slack_max]; `elastic` must be false
  /// under Penalty (the caller checks it), slack_max > 0.
  RelaxedNlp(const Mpcc& problem, RelaxationKind kind, bool elastic, double slack_max);

  int variable_count() const { return n_; }
  int original_constraint_count() const { return m_; }
  int total_constraint_count() const { return m_total_; }
  int sign_row_count() const { return n_sign_rows_; }
  int pair_count() const { return n_pairs_; }
  bool elastic() const { return elastic_; }
  /// Pairs whose relaxation row holds the elastic slack (0 unless elastic()).
  int elastic_pair_count() const { return n_elastic_pairs_; }
  /// Sign row of side s (2j: G_j, 2j+1: H_j), -1 when the side has none (pruned by its bounds).
  int sign_row_of_side(int s) const { return sign_row_of_side_[s]; }
  /// Value of side s at x.
  double side_value(int s, const Eigen::Ref<const Eigen::VectorXd>& x) const { return side_value(s, x.data()); }
  /// The weight of pair j's product in the Lagrangian at a solution with multipliers lambda (size
  /// m_total) of this NLP at `sigma`: Scholtes: the relaxation row's multiplier; Penalty: rho.
  double pair_weight(const Eigen::VectorXd& lambda, int j, double sigma) const {
    return kind_ != RelaxationKind::Penalty ? lambda[m_ + n_sign_rows_ + j] : 1.0 / sigma;
  }
  /// The branch of every pair for a polish step at x: zero_side[j] = 0 sets G_j = 0, 1 sets
  /// H_j = 0: the side with the smaller |side(x)| / ||a_side||_2 (the Euclidean distance from x
  /// to the hyperplane side = 0; ties: G_j). `biactive` counts the pairs with both distances
  /// below `biactive_threshold`.
  /// With `previous` (the previous successful step's x, at sigma_previous > sigma) the trend
  /// overrides the distances: when the side the distances pick does not shrink from previous to
  /// x (ratio >= sqrt(sigma / sigma_previous)) while the other one does, the other one is zeroed
  /// (`by_trend` counts these pairs): G = 1e-5 holding still against H = 1e-4 falling with sigma
  /// is the branch H = 0.
  /// `biactive_pairs` (optional) receives the biactive pairs' indices, largest first: by the
  /// larger of the pair's two distances, descending (ties: lower index first), the order in
  /// which the polish's fallback flips them one at a time.
  std::vector<int> choose_branches(const Eigen::Ref<const Eigen::VectorXd>& x, double biactive_threshold,
                                   int* biactive, const Eigen::VectorXd* previous = nullptr,
                                   double sigma_ratio = 0.1, int* by_trend = nullptr,
                                   std::vector<int>* biactive_pairs = nullptr) const;
  const Eigen::VectorXd& x_lower() const { return x_lower_; }
  const Eigen::VectorXd& x_upper() const { return x_upper_; }
  const Eigen::VectorXd& g_lower() const { return g_lower_; }
  const Eigen::VectorXd& g_upper() const { return g_upper_; }

  /// Scholtes: the bound of the relaxation rows; Penalty: rho = 1 / sigma.
  void set_sigma(double sigma) { sigma_ = sigma; }

  /// The point of the next solve; with multipliers (sizes m_total, n, n) Ipopt may warm start.
  void set_start(const Eigen::VectorXd& x);
  void set_start(const Eigen::VectorXd& x, const Eigen::VectorXd& lambda, const Eigen::VectorXd& z_lower,
                 const Eigen::VectorXd& z_upper);
  /// The elastic slack's start and its bound multipliers (used when elastic()); set after set_start.
  void set_slack_start(double s, double z_lower, double z_upper) {
    start_slack_ = s;
    start_slack_z_lower_ = z_lower;
    start_slack_z_upper_ = z_upper;
  }

  /// Filled by finalize_solution (has_result() false when Ipopt returned no iterate).
  bool has_result() const { return result_.present; }
  void clear_result() { result_.present = false; }
  const Eigen::VectorXd& result_x() const { return result_.x; }
  const Eigen::VectorXd& result_lambda() const { return result_.lambda; }  ///< size m_total
  const Eigen::VectorXd& result_z_lower() const { return result_.z_lower; }
  const Eigen::VectorXd& result_z_upper() const { return result_.z_upper; }
  /// The elastic slack of the last result and its bound multipliers (0 unless elastic()).
  double result_slack() const { return result_slack_; }
  double result_slack_z_lower() const { return result_slack_z_lower_; }
  double result_slack_z_upper() const { return result_slack_z_upper_; }

  /// max_j |G_j(x) H_j(x)| and the pair attaining it (-1 without pairs).
  double complementarity(const Eigen::Ref<const Eigen::VectorXd>& x, int* worst_pair = nullptr) const;
  /// Largest violation of the original MPCC at x: bounds, g, and the sides' signs; `worst`, when
  /// given, gets the name of the bound, row or side attaining it ("" when nothing is violated).
  /// Uses an internal buffer: not for concurrent calls.
  double constraint_violation(const Eigen::Ref<const Eigen::VectorXd>& x, std::string* worst = nullptr);

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
  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index m, const Ipopt::Number* g,
                         const Ipopt::Number* lambda, Ipopt::Number obj_value, const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override;

 private:
  /// Value of side s (2j: G_j, 2j+1: H_j) at x.
  double side_value(int s, const double* x) const {
    double v = side_constant_[s];
    for (int t = side_ptr_[s]; t < side_ptr_[s + 1]; ++t) v += side_coef_[t] * x[side_var_[t]];
    return v;
  }

  /// Is pair j's relaxation row smoothed (G_j H_j = sigma)?
  bool smoothed(int j) const;

  const Mpcc& problem_;
  RelaxationKind kind_;
  int n_ = 0, m_ = 0, n_pairs_ = 0, n_sign_rows_ = 0, m_total_ = 0;
  double sigma_ = 1.0;
  // The l-infinity elastic slack (class comment): Ipopt sees n_ + 1 variables, the slack last.
  bool elastic_ = false;
  double slack_max_ = 0.0;
  int n_elastic_pairs_ = 0;
  int slack_jac_offset_ = 0;             ///< first of its Jacobian entries (-1, one per elastic row)
  std::vector<char> pair_elastic_;       ///< per pair: its row holds the slack
  double start_slack_ = 0.0, start_slack_z_lower_ = 0.0, start_slack_z_upper_ = 0.0;
  double result_slack_ = 0.0, result_slack_z_lower_ = 0.0, result_slack_z_upper_ = 0.0;
  int ipopt_n() const { return n_ + (elastic_ ? 1 : 0); }

  friend class BranchNlp;

  Eigen::VectorXd x_lower_, x_upper_, g_lower_, g_upper_;

  // Sides in compressed rows: side s has terms [side_ptr_[s], side_ptr_[s + 1]).
  std::vector<int> side_ptr_, side_var_;
  std::vector<double> side_coef_, side_constant_;
  std::vector<int> sign_row_side_;  ///< per sign row: the (first) side it bounds
  std::vector<int> sign_row_of_side_;  ///< per side: its sign row, -1 for none
  std::vector<double> side_norm_;      ///< per side: ||a||_2

  // Jacobian: unique (row, col) positions; the problem's entries are scattered through
  // jac_map_; then the sign rows' constant entries; then per pair its relaxation row's entries,
  // [pair_jac_ptr_[j], pair_jac_ptr_[j + 1]) at positions relax_jac_offset_ + that range.
  std::vector<int> jac_row_, jac_col_, jac_map_;
  std::vector<double> sign_jac_value_;
  int sign_jac_offset_ = 0, relax_jac_offset_ = 0;
  std::vector<int> pair_jac_ptr_;
  std::vector<double> pair_jac_a_g_, pair_jac_a_h_;  ///< coefficients of the variable in G_j, H_j

  // Hessian (lower triangle): unique positions; the problem's entries scattered through
  // hess_map_; per pair the constant a_G a_H' + a_H a_G' entries (position, coefficient),
  // [pair_hess_ptr_[j], pair_hess_ptr_[j + 1]).
  std::vector<int> hess_row_, hess_col_, hess_map_;
  std::vector<int> pair_hess_ptr_, pair_hess_pos_;
  std::vector<double> pair_hess_coef_;

  // Workspaces of the callbacks.
  Eigen::VectorXd jac_buffer_, hess_buffer_, g_buffer_, zero_multipliers_;

  // Start of the next solve.
  Eigen::VectorXd start_x_, start_lambda_, start_z_lower_, start_z_upper_;
  bool start_has_multipliers_ = false;

  NlpResult result_;  ///< output of the last solve
};

/// The branch NLP (BNLP) of a polish step: the original problem with every pair fixed to one
/// branch, over the same n variables:
///   min f(x)  s.t.  g_lower <= g(x) <= g_upper,  x in the branch bounds,
///                   Z_j(x) = 0  for the chosen zero side Z_j of every pair j,
///                   O_j(x) >= 0 for the other side O_j,
/// with no product rows. A zero side becomes bounds when it can: when its interval_lower over
/// the original bounds is 0 (up to rounding), Z_j = 0 holds exactly when every variable of it
/// sits at the bound that attains the minimum, so those variables are fixed there (x_l = x_u;
/// a single variable x_i with lower bound 0, FESD's 1 - alpha and sums of alpha or of 1 - alpha
/// over alpha in [0, 1]); a side with one variable, a x_i + c, fixes x_i = -c / a. Ipopt's
/// default fixed_variable_treatment = make_parameter takes fixed variables out of the problem.
/// Fixings that contradict each other or the bounds make the branch infeasible before any
/// solve (infeasible() and why()). Every other zero side gets an equality row; an other side
/// gets a >= 0 row unless the branch bounds keep it >= 0 (interval_lower, as RelaxedNlp's sign
/// rows) or it is also a zero side; identical expressions share one row, and a row whose
/// variables are all fixed is checked once here instead of being handed to Ipopt.
/// Rows: [0, m) the problem's, [m, m + n_eq) the equality rows, then the inequality rows.
/// Built once per polish (allocation here is fine); the callbacks allocate nothing.
class BranchNlp : public Ipopt::TNLP {
 public:
  /// `relaxed` supplies the problem, its bounds, sides and merged structures; it must outlive
  /// this object. zero_side as RelaxedNlp::choose_branches.
  BranchNlp(const RelaxedNlp& relaxed, const std::vector<int>& zero_side);

  bool infeasible() const { return !why_.empty(); }
  const std::string& why() const { return why_; }
  int fixed_variable_count() const { return n_fixed_; }
  int equality_row_count() const { return n_eq_; }
  int inequality_row_count() const { return n_ineq_; }
  int total_constraint_count() const { return m_total_; }

  /// Warm start from a solution of the relaxed NLP at sigma (x, its multipliers of size
  /// relaxed.total_constraint_count(), z_L, z_U): the problem's rows keep their multipliers; an
  /// equality row Z = 0 starts with the multiplier of Z's sign row plus, per pair with that zero
  /// side, the pair's weight times its other side (the relaxed Lagrangian's term w Z O has the
  /// gradient w (O a_Z + Z a_O) ~ w O a_Z at Z ~ 0); an inequality row with its sign row's.
  void set_start(const Eigen::VectorXd& x, const Eigen::VectorXd& relaxed_lambda, const Eigen::VectorXd& z_lower,
                 const Eigen::VectorXd& z_upper, double sigma);

  bool has_result() const { return result_.present; }
  const Eigen::VectorXd& result_x() const { return result_.x; }
  const Eigen::VectorXd& result_lambda() const { return result_.lambda; }  ///< size m_total
  /// Bound multipliers as Ipopt reports them, except for the fixed variables (x_l = x_u in the
  /// branch, among them any the problem fixes itself), for which Ipopt 3.11 reports zeros:
  /// z_L - z_U = grad f + J' lambda there (the branch Lagrangian's stationarity), split into
  /// its positive and negative parts.
  const Eigen::VectorXd& result_z_lower() const { return result_.z_lower; }
  const Eigen::VectorXd& result_z_upper() const { return result_.z_upper; }

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
  /// Stores the result; completes the fixed variables' bound multipliers (result_z_lower).
  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index m, const Ipopt::Number* g,
                         const Ipopt::Number* lambda, Ipopt::Number obj_value, const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override;

 private:
  const RelaxedNlp& relaxed_;
  const Mpcc& problem_;
  int n_ = 0, m_ = 0, n_eq_ = 0, n_ineq_ = 0, m_total_ = 0, n_fixed_ = 0;
  std::string why_;
  Eigen::VectorXd x_lower_, x_upper_;  ///< the branch bounds
  std::vector<int> row_side_;          ///< per extra row (equality, then inequality): its side
  /// Per equality row: the other sides of the pairs whose zero side it is.
  std::vector<std::vector<int>> eq_row_other_sides_;

  // Jacobian: the problem's merged entries (RelaxedNlp's first sign_jac_offset_), then the
  // extra rows' constant entries.
  std::vector<int> jac_row_, jac_col_;
  std::vector<double> row_jac_value_;
  int row_jac_offset_ = 0;

  Eigen::VectorXd jac_buffer_, hess_buffer_, gradient_buffer_, zero_multipliers_;
  Eigen::VectorXd start_x_, start_lambda_, start_z_lower_, start_z_upper_;
  NlpResult result_;
  bool has_fixed_ = false;  ///< some x_lower_[i] == x_upper_[i]
};

}  // namespace saltus::timefreezing::detail
