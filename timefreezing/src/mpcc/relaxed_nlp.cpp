#include "relaxed_nlp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <utility>

namespace saltus::timefreezing::detail {

namespace {

using Terms = std::vector<std::pair<int, double>>;

Terms sorted_terms(const AffineExpression& e) {
  Terms t = e.terms;
  std::sort(t.begin(), t.end());
  return t;
}

bool all_finite(const double* v, int size) {
  for (int i = 0; i < size; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

}  // namespace

double interval_lower(const int* var, const double* coef, int count, double constant, const Eigen::VectorXd& x_lower,
                      const Eigen::VectorXd& x_upper, double* magnitude) {
  double lower = constant, size = std::abs(constant);
  for (int t = 0; t < count; ++t) {
    const double a = coef[t];
    if (a == 0.0) continue;
    // x_lower < +inf and x_upper > -inf (validate_problem): the product is finite or -inf.
    const double bound = a > 0.0 ? x_lower[var[t]] : x_upper[var[t]];
    lower += a * bound;
    size += std::abs(a * bound);
  }
  if (magnitude) *magnitude = size;
  return lower;
}

double interval_slack(double magnitude) { return 8.0 * std::numeric_limits<double>::epsilon() * magnitude; }

void NlpResult::resize(int n, int m) {
  x = Eigen::VectorXd::Zero(n);
  lambda = Eigen::VectorXd::Zero(m);
  z_lower = Eigen::VectorXd::Zero(n);
  z_upper = Eigen::VectorXd::Zero(n);
  present = false;
}

bool NlpResult::store(const double* x_in, const double* z_L, const double* z_U, const double* lambda_in) {
  if (x_in == nullptr) return false;
  std::copy_n(x_in, x.size(), x.data());
  if (z_L) std::copy_n(z_L, z_lower.size(), z_lower.data());
  else z_lower.setZero();
  if (z_U) std::copy_n(z_U, z_upper.size(), z_upper.data());
  else z_upper.setZero();
  if (lambda_in) std::copy_n(lambda_in, lambda.size(), lambda.data());
  else lambda.setZero();
  present = true;
  return true;
}

RelaxedNlp::RelaxedNlp(const Mpcc& problem, RelaxationKind kind) : RelaxedNlp(problem, kind, false, 0.0) {}

bool RelaxedNlp::smoothed(int j) const {
  return kind_ == RelaxationKind::Smoothing && problem_.complementarity_pairs()[static_cast<std::size_t>(j)].smoothable;
}

RelaxedNlp::RelaxedNlp(const Mpcc& problem, RelaxationKind kind, bool elastic, double slack_max)
    : problem_(problem), kind_(kind), elastic_(elastic && kind != RelaxationKind::Penalty), slack_max_(slack_max) {
  n_ = problem.variable_count();
  m_ = problem.constraint_count();
  x_lower_.resize(n_);
  x_upper_.resize(n_);
  g_lower_.resize(m_);
  g_upper_.resize(m_);
  problem.bounds(x_lower_, x_upper_, g_lower_, g_upper_);

  const std::vector<ComplementarityPair>& pairs = problem.complementarity_pairs();
  n_pairs_ = static_cast<int>(pairs.size());

  // Sides, sorted by variable so that equal expressions compare equal below.
  side_ptr_.assign(1, 0);
  for (const ComplementarityPair& p : pairs) {
    for (const AffineExpression* e : {&p.left, &p.right}) {
      for (const auto& [i, a] : sorted_terms(*e)) {
        side_var_.push_back(i);
        side_coef_.push_back(a);
      }
      side_ptr_.push_back(static_cast<int>(side_var_.size()));
      side_constant_.push_back(e->constant);
    }
  }

  side_norm_.resize(2 * n_pairs_);
  for (int s = 0; s < 2 * n_pairs_; ++s) {
    double sum = 0.0;
    for (int t = side_ptr_[s]; t < side_ptr_[s + 1]; ++t) sum += side_coef_[t] * side_coef_[t];
    side_norm_[s] = std::sqrt(sum);
  }

  // Sign rows: one per distinct side that its bounds do not already keep >= 0. Row pruning: the
  // interval bound of the side over the variable bounds (the single variable with lower bound
  // >= 0 is its simplest case). With bound_relax_factor = 0 Ipopt keeps the bounds exactly, so
  // the side stays >= 0 (up to the rounding allowed by interval_slack).
  std::map<std::pair<Terms, double>, int> row_of_side;
  sign_row_of_side_.assign(2 * n_pairs_, -1);
  for (int s = 0; s < 2 * n_pairs_; ++s) {
    const ComplementarityPair& p = pairs[s / 2];
    const AffineExpression& e = (s % 2 == 0) ? p.left : p.right;
    const int single = e.single_variable();
    if (single >= 0 && x_lower_[single] >= 0.0) continue;
    double magnitude = 0.0;
    const double lower = interval_lower(side_var_.data() + side_ptr_[s], side_coef_.data() + side_ptr_[s],
                                        side_ptr_[s + 1] - side_ptr_[s], side_constant_[s], x_lower_, x_upper_,
                                        &magnitude);
    if (std::isfinite(lower) && lower >= -interval_slack(magnitude)) continue;
    const auto [it, inserted] = row_of_side.emplace(std::make_pair(sorted_terms(e), e.constant), n_sign_rows_);
    if (inserted) {
      sign_row_side_.push_back(s);
      ++n_sign_rows_;
    }
    sign_row_of_side_[s] = it->second;
  }
  const bool relaxation_rows = kind_ != RelaxationKind::Penalty;
  m_total_ = m_ + n_sign_rows_ + (relaxation_rows ? n_pairs_ : 0);

  // Jacobian: the problem's entries merged into unique positions (ordered by row, column).
  const std::vector<SparseEntry>& jac = problem.jacobian_structure();
  std::map<std::pair<int, int>, int> jac_position;
  for (const SparseEntry& e : jac) jac_position.emplace(std::make_pair(e.row, e.col), 0);
  for (auto& [rc, index] : jac_position) {
    index = static_cast<int>(jac_row_.size());
    jac_row_.push_back(rc.first);
    jac_col_.push_back(rc.second);
  }
  jac_map_.reserve(jac.size());
  for (const SparseEntry& e : jac) jac_map_.push_back(jac_position.at({e.row, e.col}));
  // Sign rows and relaxation rows are rows of their own: unique by construction (the sides'
  // variables are distinct, validate_problem).
  sign_jac_offset_ = static_cast<int>(jac_row_.size());
  for (int r = 0; r < n_sign_rows_; ++r) {
    const int s = sign_row_side_[r];
    for (int t = side_ptr_[s]; t < side_ptr_[s + 1]; ++t) {
      jac_row_.push_back(m_ + r);
      jac_col_.push_back(side_var_[t]);
      sign_jac_value_.push_back(side_coef_[t]);
    }
  }
  relax_jac_offset_ = static_cast<int>(jac_row_.size());
  pair_jac_ptr_.assign(1, 0);
  if (relaxation_rows) {
    for (int j = 0; j < n_pairs_; ++j) {
      // The row G_j H_j has an entry at every variable of either side; a variable in both
      // sides gets one entry with both coefficients.
      std::map<int, std::pair<double, double>> coefficients;
      for (int t = side_ptr_[2 * j]; t < side_ptr_[2 * j + 1]; ++t) coefficients[side_var_[t]].first = side_coef_[t];
      for (int t = side_ptr_[2 * j + 1]; t < side_ptr_[2 * j + 2]; ++t)
        coefficients[side_var_[t]].second = side_coef_[t];
      for (const auto& [i, a] : coefficients) {
        jac_row_.push_back(m_ + n_sign_rows_ + j);
        jac_col_.push_back(i);
        pair_jac_a_g_.push_back(a.first);
        pair_jac_a_h_.push_back(a.second);
      }
      pair_jac_ptr_.push_back(static_cast<int>(pair_jac_a_g_.size()));
    }
  }
  // The elastic slack's column: one entry per inequality-relaxed row, after all the others.
  slack_jac_offset_ = static_cast<int>(jac_row_.size());
  pair_elastic_.assign(static_cast<std::size_t>(n_pairs_), 0);
  if (elastic_) {
    for (int j = 0; j < n_pairs_; ++j) {
      if (smoothed(j)) continue;
      pair_elastic_[static_cast<std::size_t>(j)] = 1;
      ++n_elastic_pairs_;
      jac_row_.push_back(m_ + n_sign_rows_ + j);
      jac_col_.push_back(n_);
    }
  }

  // Hessian, lower triangle: the problem's entries and the pairs' a_G a_H' + a_H a_G', merged.
  // The pair term's entry (r, c), r > c, is a_G[r] a_H[c] + a_G[c] a_H[r]: the loop over
  // (i in G, k in H) meets it once as (r, c) and once as (c, r), both mapped to (r, c). The
  // diagonal entry is 2 a_G[r] a_H[r] but is met once, hence the factor 2.
  const std::vector<SparseEntry>& hess = problem.hessian_structure();
  std::map<std::pair<int, int>, int> hess_position;
  for (const SparseEntry& e : hess) hess_position.emplace(std::make_pair(e.row, e.col), 0);
  auto lower = [](int i, int k) { return std::make_pair(std::max(i, k), std::min(i, k)); };
  for (int j = 0; j < n_pairs_; ++j)
    for (int t = side_ptr_[2 * j]; t < side_ptr_[2 * j + 1]; ++t)
      for (int u = side_ptr_[2 * j + 1]; u < side_ptr_[2 * j + 2]; ++u)
        hess_position.emplace(lower(side_var_[t], side_var_[u]), 0);
  for (auto& [rc, index] : hess_position) {
    index = static_cast<int>(hess_row_.size());
    hess_row_.push_back(rc.first);
    hess_col_.push_back(rc.second);
  }
  hess_map_.reserve(hess.size());
  for (const SparseEntry& e : hess) hess_map_.push_back(hess_position.at({e.row, e.col}));
  pair_hess_ptr_.assign(1, 0);
  for (int j = 0; j < n_pairs_; ++j) {
    std::map<int, double> merged;  // unique position -> coefficient
    for (int t = side_ptr_[2 * j]; t < side_ptr_[2 * j + 1]; ++t)
      for (int u = side_ptr_[2 * j + 1]; u < side_ptr_[2 * j + 2]; ++u) {
        const int i = side_var_[t], k = side_var_[u];
        merged[hess_position.at(lower(i, k))] += (i == k ? 2.0 : 1.0) * side_coef_[t] * side_coef_[u];
      }
    for (const auto& [position, coefficient] : merged) {
      pair_hess_pos_.push_back(position);
      pair_hess_coef_.push_back(coefficient);
    }
    pair_hess_ptr_.push_back(static_cast<int>(pair_hess_pos_.size()));
  }

  jac_buffer_.resize(static_cast<Eigen::Index>(jac.size()));
  hess_buffer_.resize(static_cast<Eigen::Index>(hess.size()));
  g_buffer_.resize(m_);
  zero_multipliers_ = Eigen::VectorXd::Zero(m_);
  start_x_ = Eigen::VectorXd::Zero(n_);
  start_lambda_ = Eigen::VectorXd::Zero(m_total_);
  start_z_lower_ = Eigen::VectorXd::Zero(n_);
  start_z_upper_ = Eigen::VectorXd::Zero(n_);
  result_.resize(n_, m_total_);
}

void RelaxedNlp::set_start(const Eigen::VectorXd& x) {
  start_x_ = x;
  start_has_multipliers_ = false;
}

void RelaxedNlp::set_start(const Eigen::VectorXd& x, const Eigen::VectorXd& lambda, const Eigen::VectorXd& z_lower,
                           const Eigen::VectorXd& z_upper) {
  start_x_ = x;
  start_lambda_ = lambda;
  start_z_lower_ = z_lower;
  start_z_upper_ = z_upper;
  start_has_multipliers_ = true;
}

double RelaxedNlp::complementarity(const Eigen::Ref<const Eigen::VectorXd>& x, int* worst_pair) const {
  double worst = 0.0;
  int which = -1;
  for (int j = 0; j < n_pairs_; ++j) {
    const double product = std::abs(side_value(2 * j, x.data()) * side_value(2 * j + 1, x.data()));
    // NaN compares false: a NaN product is reported as the worst pair.
    if (which < 0 || product > worst || std::isnan(product)) {
      worst = product;
      which = j;
      if (std::isnan(product)) break;
    }
  }
  if (worst_pair) *worst_pair = which;
  return worst;
}

std::vector<int> RelaxedNlp::choose_branches(const Eigen::Ref<const Eigen::VectorXd>& x, double biactive_threshold,
                                             int* biactive, const Eigen::VectorXd* previous, double sigma_ratio,
                                             int* by_trend, std::vector<int>* biactive_pairs) const {
  std::vector<int> zero_side(static_cast<std::size_t>(n_pairs_), 0);
  int both = 0, trend = 0;
  std::vector<std::pair<double, int>> biactive_by_size;  // (larger distance, pair)
  const double shrinking = std::sqrt(sigma_ratio);
  auto ratio = [&](int s) {
    const double before = std::abs(side_value(s, previous->data()));
    return before > 0.0 ? std::abs(side_value(s, x.data())) / before : std::numeric_limits<double>::infinity();
  };
  auto distance = [&](int s) {
    const double v = std::abs(side_value(s, x.data()));
    if (side_norm_[s] > 0.0) return v / side_norm_[s];
    return v == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
  };
  for (int j = 0; j < n_pairs_; ++j) {
    const double dg = distance(2 * j), dh = distance(2 * j + 1);
    int zero = dh < dg ? 1 : 0;
    if (previous != nullptr && previous->size() == n_) {
      const double r_zero = ratio(2 * j + zero), r_other = ratio(2 * j + 1 - zero);
      if (r_zero >= shrinking && r_other < shrinking) {
        zero = 1 - zero;
        ++trend;
      }
    }
    zero_side[static_cast<std::size_t>(j)] = zero;
    if (dg < biactive_threshold && dh < biactive_threshold) {
      ++both;
      if (biactive_pairs) biactive_by_size.emplace_back(std::max(dg, dh), j);
    }
  }
  if (biactive) *biactive = both;
  if (by_trend) *by_trend = trend;
  if (biactive_pairs) {
    std::stable_sort(biactive_by_size.begin(), biactive_by_size.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    biactive_pairs->clear();
    for (const auto& entry : biactive_by_size) biactive_pairs->push_back(entry.second);
  }
  return zero_side;
}

double RelaxedNlp::constraint_violation(const Eigen::Ref<const Eigen::VectorXd>& x, std::string* worst) {
  double violation = 0.0;
  // Where the largest violation is: 0 bound i, 1 row i, 2 side i (named only when asked).
  int kind = -1, index = -1;
  auto account = [&](double v, int k, int i) {
    if (std::isnan(v)) v = std::numeric_limits<double>::infinity();
    if (v > violation) {
      violation = v;
      kind = k;
      index = i;
    }
  };
  for (int i = 0; i < n_; ++i) account(std::max(x_lower_[i] - x[i], x[i] - x_upper_[i]), 0, i);
  if (m_ > 0) {
    problem_.constraints(x, g_buffer_);
    for (int j = 0; j < m_; ++j) account(std::max(g_lower_[j] - g_buffer_[j], g_buffer_[j] - g_upper_[j]), 1, j);
  }
  for (int s = 0; s < 2 * n_pairs_; ++s) account(-side_value(s, x.data()), 2, s);
  if (worst != nullptr)
    *worst = kind == 0   ? "bound of " + problem_.variable_name(index)
             : kind == 1 ? problem_.constraint_name(index)
             : kind == 2 ? std::string(index % 2 == 0 ? "left" : "right") + " side of " +
                               problem_.complementarity_pairs()[static_cast<std::size_t>(index / 2)].name
                         : std::string();
  return violation;
}

bool RelaxedNlp::get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                              IndexStyleEnum& index_style) {
  n = ipopt_n();
  m = m_total_;
  nnz_jac_g = static_cast<Ipopt::Index>(jac_row_.size());
  nnz_h_lag = static_cast<Ipopt::Index>(hess_row_.size());
  index_style = C_STYLE;
  return true;
}

bool RelaxedNlp::get_bounds_info(Ipopt::Index, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index,
                                 Ipopt::Number* g_l, Ipopt::Number* g_u) {
  // +-infinity is below/above Ipopt's nlp_lower/upper_bound_inf (-+1e19): no bound.
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::copy_n(x_lower_.data(), n_, x_l);
  std::copy_n(x_upper_.data(), n_, x_u);
  std::copy_n(g_lower_.data(), m_, g_l);
  std::copy_n(g_upper_.data(), m_, g_u);
  for (int r = m_; r < m_ + n_sign_rows_; ++r) {
    g_l[r] = 0.0;
    g_u[r] = inf;
  }
  for (int r = m_ + n_sign_rows_, j = 0; r < m_total_; ++r, ++j) {
    // Elastic rows: G_j H_j - s <= 0.
    const bool is_elastic = pair_elastic_[static_cast<std::size_t>(j)] != 0;
    g_l[r] = smoothed(j) ? sigma_ : -inf;
    g_u[r] = is_elastic ? 0.0 : sigma_;
  }
  if (elastic_) {
    x_l[n_] = 0.0;
    x_u[n_] = slack_max_;
  }
  return true;
}

bool RelaxedNlp::get_starting_point(Ipopt::Index, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number* z_L,
                                    Ipopt::Number* z_U, Ipopt::Index, bool init_lambda, Ipopt::Number* lambda) {
  if (init_x) {
    std::copy_n(start_x_.data(), n_, x);
    if (elastic_) x[n_] = start_slack_;
  }
  // Ipopt asks for multipliers only with warm_start_init_point = yes, which the solver sets
  // only when it has them; zeros otherwise keep the request well defined.
  if (init_z) {
    for (int i = 0; i < n_; ++i) {
      z_L[i] = start_has_multipliers_ ? start_z_lower_[i] : 0.0;
      z_U[i] = start_has_multipliers_ ? start_z_upper_[i] : 0.0;
    }
    if (elastic_) {
      z_L[n_] = start_has_multipliers_ ? start_slack_z_lower_ : 0.0;
      z_U[n_] = start_has_multipliers_ ? start_slack_z_upper_ : 0.0;
    }
  }
  if (init_lambda)
    for (int r = 0; r < m_total_; ++r) lambda[r] = start_has_multipliers_ ? start_lambda_[r] : 0.0;
  return true;
}

// Every evaluation returns false on a non-finite result: Ipopt then shortens the step (or stops
// with Invalid_Number_Detected at the starting point) instead of computing with NaN.

bool RelaxedNlp::eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  double f = problem_.objective(xv);
  if (kind_ == RelaxationKind::Penalty) {
    const double rho = 1.0 / sigma_;
    for (int j = 0; j < n_pairs_; ++j) f += rho * side_value(2 * j, x) * side_value(2 * j + 1, x);
  }
  if (elastic_) f += x[n_] / sigma_;
  obj_value = f;
  return std::isfinite(f);
}

bool RelaxedNlp::eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  Eigen::Map<Eigen::VectorXd> gradient(grad_f, n_);
  problem_.objective_gradient(xv, gradient);
  if (kind_ == RelaxationKind::Penalty) {
    const double rho = 1.0 / sigma_;
    for (int j = 0; j < n_pairs_; ++j) {
      const double gv = side_value(2 * j, x), hv = side_value(2 * j + 1, x);
      for (int t = side_ptr_[2 * j]; t < side_ptr_[2 * j + 1]; ++t) grad_f[side_var_[t]] += rho * hv * side_coef_[t];
      for (int t = side_ptr_[2 * j + 1]; t < side_ptr_[2 * j + 2]; ++t)
        grad_f[side_var_[t]] += rho * gv * side_coef_[t];
    }
  }
  if (elastic_) grad_f[n_] = 1.0 / sigma_;
  return all_finite(grad_f, ipopt_n());
}

bool RelaxedNlp::eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  if (m_ > 0) {
    Eigen::Map<Eigen::VectorXd> g_original(g, m_);
    problem_.constraints(xv, g_original);
  }
  for (int r = 0; r < n_sign_rows_; ++r) g[m_ + r] = side_value(sign_row_side_[r], x);
  for (int r = m_ + n_sign_rows_, j = 0; r < m_total_; ++r, ++j)
    g[r] = side_value(2 * j, x) * side_value(2 * j + 1, x) - (pair_elastic_[static_cast<std::size_t>(j)] ? x[n_] : 0.0);
  return all_finite(g, m_total_);
}

bool RelaxedNlp::eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index nele_jac,
                            Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    std::copy(jac_row_.begin(), jac_row_.end(), iRow);
    std::copy(jac_col_.begin(), jac_col_.end(), jCol);
    return true;
  }
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  std::fill_n(values, sign_jac_offset_, 0.0);
  if (jac_buffer_.size() > 0) {
    problem_.jacobian_values(xv, jac_buffer_);
    for (Eigen::Index e = 0; e < jac_buffer_.size(); ++e) values[jac_map_[e]] += jac_buffer_[e];
  }
  std::copy(sign_jac_value_.begin(), sign_jac_value_.end(), values + sign_jac_offset_);
  if (kind_ != RelaxationKind::Penalty) {
    for (int j = 0; j < n_pairs_; ++j) {
      const double gv = side_value(2 * j, x), hv = side_value(2 * j + 1, x);
      for (int t = pair_jac_ptr_[j]; t < pair_jac_ptr_[j + 1]; ++t)
        values[relax_jac_offset_ + t] = gv * pair_jac_a_h_[t] + hv * pair_jac_a_g_[t];
    }
  }
  std::fill(values + slack_jac_offset_, values + nele_jac, -1.0);  // the elastic slack's column
  return all_finite(values, nele_jac);
}

bool RelaxedNlp::eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
                        const Ipopt::Number* lambda, bool, Ipopt::Index nele_hess, Ipopt::Index* iRow,
                        Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    std::copy(hess_row_.begin(), hess_row_.end(), iRow);
    std::copy(hess_col_.begin(), hess_col_.end(), jCol);
    return true;
  }
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  std::fill_n(values, nele_hess, 0.0);
  if (hess_buffer_.size() > 0) {
    // Ipopt passes no multipliers only when there are no constraints at all (its derivative
    // checker, m_total == 0).
    if (lambda != nullptr) {
      const Eigen::Map<const Eigen::VectorXd> multipliers(lambda, m_);
      problem_.hessian_values(xv, obj_factor, multipliers, hess_buffer_);
    } else {
      problem_.hessian_values(xv, obj_factor, zero_multipliers_, hess_buffer_);
    }
    for (Eigen::Index e = 0; e < hess_buffer_.size(); ++e) values[hess_map_[e]] += hess_buffer_[e];
  }
  for (int j = 0; j < n_pairs_; ++j) {
    const double weight = (kind_ != RelaxationKind::Penalty)
                              ? (lambda != nullptr ? lambda[m_ + n_sign_rows_ + j] : 0.0)
                              : obj_factor / sigma_;
    for (int t = pair_hess_ptr_[j]; t < pair_hess_ptr_[j + 1]; ++t)
      values[pair_hess_pos_[t]] += weight * pair_hess_coef_[t];
  }
  return all_finite(values, nele_hess);
}

void RelaxedNlp::finalize_solution(Ipopt::SolverReturn, Ipopt::Index, const Ipopt::Number* x,
                                   const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index,
                                   const Ipopt::Number*, const Ipopt::Number* lambda, Ipopt::Number,
                                   const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) {
  // store() copies the problem's n entries; the slack, Ipopt's last variable, separately.
  if (!result_.store(x, z_L, z_U, lambda) || !elastic_) return;
  result_slack_ = x[n_];
  result_slack_z_lower_ = z_L ? z_L[n_] : 0.0;
  result_slack_z_upper_ = z_U ? z_U[n_] : 0.0;
}

// ---- BranchNlp

BranchNlp::BranchNlp(const RelaxedNlp& relaxed, const std::vector<int>& zero_side)
    : relaxed_(relaxed), problem_(relaxed.problem_) {
  const RelaxedNlp& r = relaxed;
  n_ = r.n_;
  m_ = r.m_;
  x_lower_ = r.x_lower_;
  x_upper_ = r.x_upper_;
  std::vector<char> fixed(static_cast<std::size_t>(n_), 0);
  std::ostringstream why;
  why.precision(17);
  auto side_name = [&](int s) {
    const ComplementarityPair& p = problem_.complementarity_pairs()[static_cast<std::size_t>(s / 2)];
    return std::string(s % 2 == 0 ? "left" : "right") + " side of " + p.name;
  };
  // Fix x_i = v; false (and why_) when that contradicts an earlier fixing or the bounds.
  auto fix = [&](int i, double v, int s) {
    if (fixed[static_cast<std::size_t>(i)]) {
      if (std::abs(x_lower_[i] - v) <= interval_slack(std::max(1.0, std::abs(v)))) return true;
      why << "setting the " << side_name(s) << " to zero needs " << problem_.variable_name(i) << " = " << v
          << ", another pair's branch fixed it at " << x_lower_[i];
      return false;
    }
    if (v < x_lower_[i] || v > x_upper_[i]) {
      why << "setting the " << side_name(s) << " to zero needs " << problem_.variable_name(i) << " = " << v
          << ", outside its bounds [" << x_lower_[i] << ", " << x_upper_[i] << "]";
      return false;
    }
    fixed[static_cast<std::size_t>(i)] = 1;
    x_lower_[i] = x_upper_[i] = v;
    ++n_fixed_;
    return true;
  };
  auto terms_of = [&](int s) { return std::make_pair(r.side_ptr_[s], r.side_ptr_[s + 1]); };

  // Pass 1: zero sides that bounds can express.
  std::vector<int> row_zero_sides;  // zero sides that need an equality row
  bool ok = true;
  for (int j = 0; j < r.n_pairs_ && ok; ++j) {
    const int s = 2 * j + (zero_side[static_cast<std::size_t>(j)] != 0 ? 1 : 0);
    const auto [begin, end] = terms_of(s);
    double magnitude = 0.0;
    const double lower = interval_lower(r.side_var_.data() + begin, r.side_coef_.data() + begin, end - begin,
                                        r.side_constant_[s], r.x_lower_, r.x_upper_, &magnitude);
    int nonzero_terms = 0, last = -1;
    for (int t = begin; t < end; ++t)
      if (r.side_coef_[t] != 0.0) {
        ++nonzero_terms;
        last = t;
      }
    if (std::isfinite(lower) && std::abs(lower) <= interval_slack(magnitude)) {
      for (int t = begin; t < end && ok; ++t) {
        const double a = r.side_coef_[t];
        if (a != 0.0) ok = fix(r.side_var_[t], a > 0.0 ? r.x_lower_[r.side_var_[t]] : r.x_upper_[r.side_var_[t]], s);
      }
    } else if (nonzero_terms == 1) {
      const double v = -r.side_constant_[s] / r.side_coef_[last];
      ok = fix(r.side_var_[last], v == 0.0 ? 0.0 : v, s);  // no -0
    } else if (std::isfinite(lower) && lower > interval_slack(magnitude)) {
      why << "the " << side_name(s) << " is >= " << lower << " > 0 within the bounds";
      ok = false;
    } else {
      row_zero_sides.push_back(s);
    }
  }

  // Value of side s if all its variables are fixed (else NaN).
  auto fixed_value = [&](int s) {
    double v = r.side_constant_[s];
    for (int t = r.side_ptr_[s]; t < r.side_ptr_[s + 1]; ++t) {
      if (r.side_coef_[t] == 0.0) continue;
      if (!fixed[static_cast<std::size_t>(r.side_var_[t])]) return std::numeric_limits<double>::quiet_NaN();
      v += r.side_coef_[t] * x_lower_[r.side_var_[t]];
    }
    return v;
  };
  auto key_of = [&](int s) {
    Terms t;
    for (int u = r.side_ptr_[s]; u < r.side_ptr_[s + 1]; ++u) t.emplace_back(r.side_var_[u], r.side_coef_[u]);
    return std::make_pair(t, r.side_constant_[s]);
  };

  // Pass 2: equality rows, one per distinct expression.
  std::map<std::pair<Terms, double>, int> eq_row_of;
  for (std::size_t k = 0; k < row_zero_sides.size() && ok; ++k) {
    const int s = row_zero_sides[k];
    const double v = fixed_value(s);
    if (!std::isnan(v)) {
      double magnitude = 0.0;
      interval_lower(r.side_var_.data() + r.side_ptr_[s], r.side_coef_.data() + r.side_ptr_[s],
                     r.side_ptr_[s + 1] - r.side_ptr_[s], r.side_constant_[s], x_lower_, x_upper_, &magnitude);
      if (std::abs(v) > interval_slack(magnitude)) {
        why << "the " << side_name(s) << " is " << v << " != 0 with the variables other pairs' branches fixed";
        ok = false;
      }
      continue;
    }
    const auto [it, inserted] = eq_row_of.emplace(key_of(s), n_eq_);
    if (inserted) {
      row_side_.push_back(s);
      eq_row_other_sides_.emplace_back();
      ++n_eq_;
    }
    eq_row_other_sides_[static_cast<std::size_t>(it->second)].push_back(s ^ 1);
  }

  // Pass 3: inequality rows for the other sides the branch bounds do not keep >= 0.
  std::map<std::pair<Terms, double>, int> ineq_row_of;
  for (int j = 0; j < r.n_pairs_ && ok; ++j) {
    const int s = 2 * j + (zero_side[static_cast<std::size_t>(j)] != 0 ? 0 : 1);
    double magnitude = 0.0;
    const double lower = interval_lower(r.side_var_.data() + r.side_ptr_[s], r.side_coef_.data() + r.side_ptr_[s],
                                        r.side_ptr_[s + 1] - r.side_ptr_[s], r.side_constant_[s], x_lower_,
                                        x_upper_, &magnitude);
    if (std::isfinite(lower) && lower >= -interval_slack(magnitude)) continue;
    const double v = fixed_value(s);
    if (!std::isnan(v)) {  // all fixed, and the interval says it is negative
      why << "the " << side_name(s) << " is " << v << " < 0 with the variables the branches fixed";
      ok = false;
      continue;
    }
    auto key = key_of(s);
    if (eq_row_of.count(key)) continue;
    if (ineq_row_of.emplace(std::move(key), n_ineq_).second) {
      row_side_.push_back(s);
      ++n_ineq_;
    }
  }
  if (!ok) why_ = why.str();
  m_total_ = m_ + n_eq_ + n_ineq_;
  has_fixed_ = (x_lower_.array() == x_upper_.array()).any();

  // Jacobian: the problem's merged entries, then the extra rows.
  row_jac_offset_ = r.sign_jac_offset_;
  jac_row_.assign(r.jac_row_.begin(), r.jac_row_.begin() + row_jac_offset_);
  jac_col_.assign(r.jac_col_.begin(), r.jac_col_.begin() + row_jac_offset_);
  for (int k = 0; k < n_eq_ + n_ineq_; ++k) {
    const int s = row_side_[static_cast<std::size_t>(k)];
    for (int t = r.side_ptr_[s]; t < r.side_ptr_[s + 1]; ++t) {
      jac_row_.push_back(m_ + k);
      jac_col_.push_back(r.side_var_[t]);
      row_jac_value_.push_back(r.side_coef_[t]);
    }
  }

  jac_buffer_.resize(r.jac_buffer_.size());
  hess_buffer_.resize(r.hess_buffer_.size());
  gradient_buffer_.resize(n_);
  zero_multipliers_ = Eigen::VectorXd::Zero(m_);
  start_x_ = Eigen::VectorXd::Zero(n_);
  start_lambda_ = Eigen::VectorXd::Zero(m_total_);
  start_z_lower_ = Eigen::VectorXd::Zero(n_);
  start_z_upper_ = Eigen::VectorXd::Zero(n_);
  result_.resize(n_, m_total_);
}

void BranchNlp::set_start(const Eigen::VectorXd& x, const Eigen::VectorXd& relaxed_lambda,
                          const Eigen::VectorXd& z_lower, const Eigen::VectorXd& z_upper, double sigma) {
  const RelaxedNlp& r = relaxed_;
  start_x_ = x;
  start_z_lower_ = z_lower;
  start_z_upper_ = z_upper;
  start_lambda_.setZero();
  start_lambda_.head(m_) = relaxed_lambda.head(m_);
  for (int k = 0; k < n_eq_ + n_ineq_; ++k) {
    const int s = row_side_[static_cast<std::size_t>(k)];
    const int sign_row = r.sign_row_of_side(s);
    double mu = sign_row >= 0 ? relaxed_lambda[m_ + sign_row] : 0.0;
    if (k < n_eq_)
      for (int other : eq_row_other_sides_[static_cast<std::size_t>(k)])
        mu += r.pair_weight(relaxed_lambda, other / 2, sigma) * r.side_value(other, x.data());
    start_lambda_[m_ + k] = mu;
  }
}

bool BranchNlp::get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                             IndexStyleEnum& index_style) {
  n = n_;
  m = m_total_;
  nnz_jac_g = static_cast<Ipopt::Index>(jac_row_.size());
  nnz_h_lag = static_cast<Ipopt::Index>(relaxed_.hess_row_.size());
  index_style = C_STYLE;
  return true;
}

bool BranchNlp::get_bounds_info(Ipopt::Index, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index,
                                Ipopt::Number* g_l, Ipopt::Number* g_u) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::copy_n(x_lower_.data(), n_, x_l);
  std::copy_n(x_upper_.data(), n_, x_u);
  std::copy_n(relaxed_.g_lower_.data(), m_, g_l);
  std::copy_n(relaxed_.g_upper_.data(), m_, g_u);
  for (int k = 0; k < n_eq_ + n_ineq_; ++k) {
    g_l[m_ + k] = 0.0;
    g_u[m_ + k] = k < n_eq_ ? 0.0 : inf;
  }
  return true;
}

bool BranchNlp::get_starting_point(Ipopt::Index, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number* z_L,
                                   Ipopt::Number* z_U, Ipopt::Index, bool init_lambda, Ipopt::Number* lambda) {
  if (init_x) std::copy_n(start_x_.data(), n_, x);
  if (init_z) {
    std::copy_n(start_z_lower_.data(), n_, z_L);
    std::copy_n(start_z_upper_.data(), n_, z_U);
  }
  if (init_lambda) std::copy_n(start_lambda_.data(), m_total_, lambda);
  return true;
}

bool BranchNlp::eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  obj_value = problem_.objective(xv);
  return std::isfinite(obj_value);
}

bool BranchNlp::eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  Eigen::Map<Eigen::VectorXd> gradient(grad_f, n_);
  problem_.objective_gradient(xv, gradient);
  return all_finite(grad_f, n_);
}

bool BranchNlp::eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  if (m_ > 0) {
    Eigen::Map<Eigen::VectorXd> g_original(g, m_);
    problem_.constraints(xv, g_original);
  }
  for (int k = 0; k < n_eq_ + n_ineq_; ++k) g[m_ + k] = relaxed_.side_value(row_side_[static_cast<std::size_t>(k)], x);
  return all_finite(g, m_total_);
}

bool BranchNlp::eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index nele_jac,
                           Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    std::copy(jac_row_.begin(), jac_row_.end(), iRow);
    std::copy(jac_col_.begin(), jac_col_.end(), jCol);
    return true;
  }
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  std::fill_n(values, row_jac_offset_, 0.0);
  if (jac_buffer_.size() > 0) {
    problem_.jacobian_values(xv, jac_buffer_);
    for (Eigen::Index e = 0; e < jac_buffer_.size(); ++e) values[relaxed_.jac_map_[e]] += jac_buffer_[e];
  }
  std::copy(row_jac_value_.begin(), row_jac_value_.end(), values + row_jac_offset_);
  return all_finite(values, nele_jac);
}

bool BranchNlp::eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
                       const Ipopt::Number* lambda, bool, Ipopt::Index nele_hess, Ipopt::Index* iRow,
                       Ipopt::Index* jCol, Ipopt::Number* values) {
  // RelaxedNlp's merged structure; the pairs' positions stay zero (no product rows here).
  if (values == nullptr) {
    std::copy(relaxed_.hess_row_.begin(), relaxed_.hess_row_.end(), iRow);
    std::copy(relaxed_.hess_col_.begin(), relaxed_.hess_col_.end(), jCol);
    return true;
  }
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  std::fill_n(values, nele_hess, 0.0);
  if (hess_buffer_.size() > 0) {
    if (lambda != nullptr) {
      const Eigen::Map<const Eigen::VectorXd> multipliers(lambda, m_);
      problem_.hessian_values(xv, obj_factor, multipliers, hess_buffer_);
    } else {
      problem_.hessian_values(xv, obj_factor, zero_multipliers_, hess_buffer_);
    }
    for (Eigen::Index e = 0; e < hess_buffer_.size(); ++e) values[relaxed_.hess_map_[e]] += hess_buffer_[e];
  }
  return all_finite(values, nele_hess);
}

void BranchNlp::finalize_solution(Ipopt::SolverReturn, Ipopt::Index, const Ipopt::Number* x,
                                  const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index,
                                  const Ipopt::Number*, const Ipopt::Number* lambda, Ipopt::Number,
                                  const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) {
  if (!result_.store(x, z_L, z_U, lambda)) return;
  if (!has_fixed_) return;
  // Ipopt 3.11 (fixed_variable_treatment = make_parameter) reports z_L = z_U = 0 for the fixed
  // variables. Their multipliers follow from the Lagrangian's gradient r = grad f + J' lambda:
  // stationarity r - z_L + z_U = 0 gives z_L = max(r, 0), z_U = max(-r, 0). For the variables the
  // branch fixed, these carry the pairs' multipliers.
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  problem_.objective_gradient(xv, gradient_buffer_);
  if (jac_buffer_.size() > 0) {
    problem_.jacobian_values(xv, jac_buffer_);
    const std::vector<SparseEntry>& jac = problem_.jacobian_structure();
    for (Eigen::Index e = 0; e < jac_buffer_.size(); ++e)
      gradient_buffer_[jac[static_cast<std::size_t>(e)].col] += result_.lambda[jac[static_cast<std::size_t>(e)].row] * jac_buffer_[e];
  }
  for (int k = 0; k < n_eq_ + n_ineq_; ++k) {
    const int s = row_side_[static_cast<std::size_t>(k)];
    for (int t = relaxed_.side_ptr_[s]; t < relaxed_.side_ptr_[s + 1]; ++t)
      gradient_buffer_[relaxed_.side_var_[t]] += result_.lambda[m_ + k] * relaxed_.side_coef_[t];
  }
  for (int i = 0; i < n_; ++i) {
    if (x_lower_[i] != x_upper_[i]) continue;
    result_.z_lower[i] = std::max(gradient_buffer_[i], 0.0);
    result_.z_upper[i] = std::max(-gradient_buffer_[i], 0.0);
  }
}

}  // namespace saltus::timefreezing::detail
