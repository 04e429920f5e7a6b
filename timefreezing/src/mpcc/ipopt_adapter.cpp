#include "ipopt_adapter.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <utility>

namespace saltus::timefreezing::detail {

namespace {

bool all_finite(const double* v, int size) {
  for (int i = 0; i < size; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

}  // namespace

ReformulatedNlp::ReformulatedNlp(const MpccLayout& layout, const Reformulation& nlp)
    : layout_(layout),
      nlp_(nlp),
      n_(layout.variable_count()),
      m_(layout.constraint_count()),
      n_pairs_(layout.pair_count()),
      n_affine_(nlp.affine_row_count()),
      m_total_(nlp.row_count(layout.constraint_count(), layout.pair_count())) {
  build_jacobian_structure();
  jac_buffer_.resize(static_cast<Eigen::Index>(layout.problem().jacobian_structure().size()));
  hess_buffer_.resize(static_cast<Eigen::Index>(layout.problem().hessian_structure().size()));
  zero_multipliers_ = Eigen::VectorXd::Zero(m_);
  gradient_buffer_.resize(n_);
  start_.x = Eigen::VectorXd::Zero(n_);
  start_.lambda = Eigen::VectorXd::Zero(m_total_);
  start_.z_lower = Eigen::VectorXd::Zero(n_);
  start_.z_upper = Eigen::VectorXd::Zero(n_);
  result_ = start_;
}

void ReformulatedNlp::build_jacobian_structure() {
  jac_row_ = layout_.jacobian_rows();
  jac_col_ = layout_.jacobian_cols();
  // The affine and product rows are rows of their own: unique by construction (the sides'
  // variables are distinct, validate_problem).
  affine_jac_offset_ = static_cast<int>(jac_row_.size());
  for (int r = 0; r < n_affine_; ++r) {
    const int s = nlp_.affine_side[static_cast<std::size_t>(r)];
    for (int t = layout_.side_begin(s); t < layout_.side_end(s); ++t) {
      jac_row_.push_back(m_ + r);
      jac_col_.push_back(layout_.term_variable(t));
      affine_jac_value_.push_back(layout_.term_coefficient(t));
    }
  }
  product_jac_offset_ = static_cast<int>(jac_row_.size());
  pair_jac_ptr_.assign(1, 0);
  if (!nlp_.product_rows) return;
  for (int j = 0; j < n_pairs_; ++j) {
    // The row G_j H_j has an entry at every variable of either side; a variable in both sides
    // gets one entry with both coefficients.
    std::map<int, std::pair<double, double>> coefficients;
    for (int t = layout_.side_begin(2 * j); t < layout_.side_end(2 * j); ++t)
      coefficients[layout_.term_variable(t)].first = layout_.term_coefficient(t);
    for (int t = layout_.side_begin(2 * j + 1); t < layout_.side_end(2 * j + 1); ++t)
      coefficients[layout_.term_variable(t)].second = layout_.term_coefficient(t);
    for (const auto& [i, a] : coefficients) {
      jac_row_.push_back(nlp_.first_product_row(m_) + j);
      jac_col_.push_back(i);
      pair_jac_a_g_.push_back(a.first);
      pair_jac_a_h_.push_back(a.second);
    }
    pair_jac_ptr_.push_back(static_cast<int>(pair_jac_a_g_.size()));
  }
}

void ReformulatedNlp::set_start(const Eigen::VectorXd& x) {
  start_.x = x;
  start_has_multipliers_ = false;
}

void ReformulatedNlp::set_start(const Eigen::VectorXd& x, const Eigen::VectorXd& lambda, const Eigen::VectorXd& z_lower,
                                const Eigen::VectorXd& z_upper) {
  start_.x = x;
  start_.lambda = lambda;
  start_.z_lower = z_lower;
  start_.z_upper = z_upper;
  start_has_multipliers_ = true;
}

bool ReformulatedNlp::get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                                   IndexStyleEnum& index_style) {
  n = n_;
  m = m_total_;
  nnz_jac_g = static_cast<Ipopt::Index>(jac_row_.size());
  nnz_h_lag = static_cast<Ipopt::Index>(layout_.hessian_rows().size());
  index_style = C_STYLE;
  return true;
}

bool ReformulatedNlp::get_bounds_info(Ipopt::Index, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index,
                                      Ipopt::Number* g_l, Ipopt::Number* g_u) {
  std::copy_n(nlp_.x_lower.data(), n_, x_l);
  std::copy_n(nlp_.x_upper.data(), n_, x_u);
  std::copy_n(layout_.g_lower().data(), m_, g_l);
  std::copy_n(layout_.g_upper().data(), m_, g_u);
  std::copy_n(nlp_.affine_lower.data(), n_affine_, g_l + m_);
  std::copy_n(nlp_.affine_upper.data(), n_affine_, g_u + m_);
  if (nlp_.product_rows) {
    std::copy_n(nlp_.product_lower.data(), n_pairs_, g_l + nlp_.first_product_row(m_));
    std::copy_n(nlp_.product_upper.data(), n_pairs_, g_u + nlp_.first_product_row(m_));
  }
  return true;
}

bool ReformulatedNlp::get_starting_point(Ipopt::Index, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number* z_L,
                                         Ipopt::Number* z_U, Ipopt::Index, bool init_lambda, Ipopt::Number* lambda) {
  if (init_x) std::copy_n(start_.x.data(), n_, x);
  // Ipopt asks for multipliers only with warm_start_init_point = yes, which the solver sets
  // only when it has them; zeros otherwise keep the request well defined.
  if (init_z) {
    for (int i = 0; i < n_; ++i) {
      z_L[i] = start_has_multipliers_ ? start_.z_lower[i] : 0.0;
      z_U[i] = start_has_multipliers_ ? start_.z_upper[i] : 0.0;
    }
  }
  if (init_lambda)
    for (int r = 0; r < m_total_; ++r) lambda[r] = start_has_multipliers_ ? start_.lambda[r] : 0.0;
  return true;
}

bool ReformulatedNlp::eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  double f = layout_.problem().objective(xv);
  if (nlp_.penalty) {
    const double rho = 1.0 / nlp_.penalty_sigma;
    for (int j = 0; j < n_pairs_; ++j) f += rho * layout_.side_value(2 * j, x) * layout_.side_value(2 * j + 1, x);
  }
  obj_value = f;
  return std::isfinite(f);
}

bool ReformulatedNlp::eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  Eigen::Map<Eigen::VectorXd> gradient(grad_f, n_);
  layout_.problem().objective_gradient(xv, gradient);
  if (nlp_.penalty) {
    const double rho = 1.0 / nlp_.penalty_sigma;
    for (int j = 0; j < n_pairs_; ++j) {
      const double gv = layout_.side_value(2 * j, x), hv = layout_.side_value(2 * j + 1, x);
      for (int t = layout_.side_begin(2 * j); t < layout_.side_end(2 * j); ++t)
        grad_f[layout_.term_variable(t)] += rho * hv * layout_.term_coefficient(t);
      for (int t = layout_.side_begin(2 * j + 1); t < layout_.side_end(2 * j + 1); ++t)
        grad_f[layout_.term_variable(t)] += rho * gv * layout_.term_coefficient(t);
    }
  }
  return all_finite(grad_f, n_);
}

bool ReformulatedNlp::eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  if (m_ > 0) {
    Eigen::Map<Eigen::VectorXd> g_original(g, m_);
    layout_.problem().constraints(xv, g_original);
  }
  for (int r = 0; r < n_affine_; ++r) g[m_ + r] = layout_.side_value(nlp_.affine_side[static_cast<std::size_t>(r)], x);
  if (nlp_.product_rows)
    for (int j = 0, r = nlp_.first_product_row(m_); j < n_pairs_; ++j, ++r)
      g[r] = layout_.side_value(2 * j, x) * layout_.side_value(2 * j + 1, x);
  return all_finite(g, m_total_);
}

bool ReformulatedNlp::eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index nele_jac,
                                 Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    std::copy(jac_row_.begin(), jac_row_.end(), iRow);
    std::copy(jac_col_.begin(), jac_col_.end(), jCol);
    return true;
  }
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  std::fill_n(values, affine_jac_offset_, 0.0);
  if (jac_buffer_.size() > 0) {
    layout_.problem().jacobian_values(xv, jac_buffer_);
    const std::vector<int>& map = layout_.jacobian_map();
    for (Eigen::Index e = 0; e < jac_buffer_.size(); ++e) values[map[static_cast<std::size_t>(e)]] += jac_buffer_[e];
  }
  std::copy(affine_jac_value_.begin(), affine_jac_value_.end(), values + affine_jac_offset_);
  if (nlp_.product_rows) {
    for (int j = 0; j < n_pairs_; ++j) {
      const double gv = layout_.side_value(2 * j, x), hv = layout_.side_value(2 * j + 1, x);
      for (int t = pair_jac_ptr_[j]; t < pair_jac_ptr_[j + 1]; ++t)
        values[product_jac_offset_ + t] = gv * pair_jac_a_h_[t] + hv * pair_jac_a_g_[t];
    }
  }
  return all_finite(values, nele_jac);
}

bool ReformulatedNlp::eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
                             const Ipopt::Number* lambda, bool, Ipopt::Index nele_hess, Ipopt::Index* iRow,
                             Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    std::copy(layout_.hessian_rows().begin(), layout_.hessian_rows().end(), iRow);
    std::copy(layout_.hessian_cols().begin(), layout_.hessian_cols().end(), jCol);
    return true;
  }
  const Eigen::Map<const Eigen::VectorXd> xv(x, n_);
  std::fill_n(values, nele_hess, 0.0);
  if (hess_buffer_.size() > 0) {
    // Ipopt passes no multipliers only when there are no constraints at all (its derivative
    // checker, m_total == 0).
    if (lambda != nullptr) {
      const Eigen::Map<const Eigen::VectorXd> multipliers(lambda, m_);
      layout_.problem().hessian_values(xv, obj_factor, multipliers, hess_buffer_);
    } else {
      layout_.problem().hessian_values(xv, obj_factor, zero_multipliers_, hess_buffer_);
    }
    const std::vector<int>& map = layout_.hessian_map();
    for (Eigen::Index e = 0; e < hess_buffer_.size(); ++e) values[map[static_cast<std::size_t>(e)]] += hess_buffer_[e];
  }
  if (!nlp_.product_rows && !nlp_.penalty) return all_finite(values, nele_hess);
  for (int j = 0; j < n_pairs_; ++j) {
    const double weight = nlp_.product_rows ? (lambda != nullptr ? lambda[nlp_.first_product_row(m_) + j] : 0.0)
                                            : obj_factor / nlp_.penalty_sigma;
    for (int t = layout_.pair_hessian_begin(j); t < layout_.pair_hessian_begin(j + 1); ++t)
      values[layout_.pair_hessian_position(t)] += weight * layout_.pair_hessian_coefficient(t);
  }
  return all_finite(values, nele_hess);
}

bool ReformulatedNlp::store(const double* x, const double* z_L, const double* z_U, const double* lambda) {
  if (x == nullptr) return false;
  std::copy_n(x, n_, result_.x.data());
  if (z_L)
    std::copy_n(z_L, n_, result_.z_lower.data());
  else
    result_.z_lower.setZero();
  if (z_U)
    std::copy_n(z_U, n_, result_.z_upper.data());
  else
    result_.z_upper.setZero();
  if (lambda)
    std::copy_n(lambda, m_total_, result_.lambda.data());
  else
    result_.lambda.setZero();
  present_ = true;
  return true;
}

void ReformulatedNlp::finalize_solution(Ipopt::SolverReturn, Ipopt::Index, const Ipopt::Number* x,
                                        const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index,
                                        const Ipopt::Number*, const Ipopt::Number* lambda, Ipopt::Number,
                                        const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) {
  if (store(x, z_L, z_U, lambda) && nlp_.complete_fixed_multipliers) complete_fixed_multipliers();
}

void ReformulatedNlp::complete_fixed_multipliers() {
  if (!(nlp_.x_lower.array() == nlp_.x_upper.array()).any()) return;
  // Ipopt 3.11 (fixed_variable_treatment = make_parameter) reports z_L = z_U = 0 for the fixed
  // variables. Their multipliers follow from the Lagrangian's gradient r = grad f + J' lambda:
  // stationarity r - z_L + z_U = 0 gives z_L = max(r, 0), z_U = max(-r, 0). For the variables a
  // branch fixed, these carry the pairs' multipliers.
  const Mpcc& problem = layout_.problem();
  problem.objective_gradient(result_.x, gradient_buffer_);
  if (jac_buffer_.size() > 0) {
    problem.jacobian_values(result_.x, jac_buffer_);
    const std::vector<SparseEntry>& jac = problem.jacobian_structure();
    for (Eigen::Index e = 0; e < jac_buffer_.size(); ++e) {
      const SparseEntry& entry = jac[static_cast<std::size_t>(e)];
      gradient_buffer_[entry.col] += result_.lambda[entry.row] * jac_buffer_[e];
    }
  }
  for (int r = 0; r < n_affine_; ++r) {
    const int s = nlp_.affine_side[static_cast<std::size_t>(r)];
    for (int t = layout_.side_begin(s); t < layout_.side_end(s); ++t)
      gradient_buffer_[layout_.term_variable(t)] += result_.lambda[m_ + r] * layout_.term_coefficient(t);
  }
  for (int i = 0; i < n_; ++i) {
    if (nlp_.x_lower[i] != nlp_.x_upper[i]) continue;
    result_.z_lower[i] = std::max(gradient_buffer_[i], 0.0);
    result_.z_upper[i] = std::max(-gradient_buffer_[i], 0.0);
  }
}

}  // namespace saltus::timefreezing::detail
