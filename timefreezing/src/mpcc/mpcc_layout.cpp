#include "mpcc_layout.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>

namespace saltus::timefreezing::detail {

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

double interval_slack(double magnitude) {
  return 8.0 * std::numeric_limits<double>::epsilon() * magnitude;
}

MpccLayout::MpccLayout(const Mpcc& problem) : problem_(problem) {
  n_ = problem.variable_count();
  m_ = problem.constraint_count();
  n_pairs_ = static_cast<int>(problem.complementarity_pairs().size());
  x_lower_.resize(n_);
  x_upper_.resize(n_);
  g_lower_.resize(m_);
  g_upper_.resize(m_);
  problem.bounds(x_lower_, x_upper_, g_lower_, g_upper_);
  read_sides();
  merge_jacobian();
  merge_hessian();
  g_buffer_.resize(m_);
}

void MpccLayout::read_sides() {
  // Sides, sorted by variable so that equal expressions compare equal (side_key).
  side_ptr_.assign(1, 0);
  for (const ComplementarityPair& p : problem_.complementarity_pairs()) {
    for (const AffineExpression* e : {&p.left, &p.right}) {
      std::vector<std::pair<int, double>> terms = e->terms;
      std::sort(terms.begin(), terms.end());
      for (const auto& [i, a] : terms) {
        side_var_.push_back(i);
        side_coef_.push_back(a);
      }
      side_ptr_.push_back(static_cast<int>(side_var_.size()));
      side_constant_.push_back(e->constant);
    }
  }
  side_norm_.resize(static_cast<std::size_t>(2 * n_pairs_));
  for (int s = 0; s < 2 * n_pairs_; ++s) {
    double sum = 0.0;
    for (int t = side_ptr_[s]; t < side_ptr_[s + 1]; ++t) sum += side_coef_[t] * side_coef_[t];
    side_norm_[s] = std::sqrt(sum);
  }
}

namespace {

using Positions = std::map<std::pair<int, int>, int>;

/// Numbers the unique positions in their order (row, then column) into rows and cols, and maps
/// every entry of `entries` to its position's number.
void number_positions(Positions& position, const std::vector<SparseEntry>& entries, std::vector<int>& rows,
                      std::vector<int>& cols, std::vector<int>& map) {
  for (auto& [rc, index] : position) {
    index = static_cast<int>(rows.size());
    rows.push_back(rc.first);
    cols.push_back(rc.second);
  }
  map.reserve(entries.size());
  for (const SparseEntry& e : entries) map.push_back(position.at({e.row, e.col}));
}

}  // namespace

void MpccLayout::merge_jacobian() {
  const std::vector<SparseEntry>& jac = problem_.jacobian_structure();
  Positions position;
  for (const SparseEntry& e : jac) position.emplace(std::make_pair(e.row, e.col), 0);
  number_positions(position, jac, jac_row_, jac_col_, jac_map_);
}

void MpccLayout::merge_hessian() {
  // Lower triangle: the problem's entries and the pairs' a_G a_H' + a_H a_G', merged. The pair
  // term's entry (r, c), r > c, is a_G[r] a_H[c] + a_G[c] a_H[r]: the loop over (i in G, k in H)
  // meets it once as (r, c) and once as (c, r), both mapped to (r, c). The diagonal entry is
  // 2 a_G[r] a_H[r] but is met once, hence the factor 2.
  const std::vector<SparseEntry>& hess = problem_.hessian_structure();
  Positions position;
  for (const SparseEntry& e : hess) position.emplace(std::make_pair(e.row, e.col), 0);
  auto lower = [](int i, int k) { return std::make_pair(std::max(i, k), std::min(i, k)); };
  for (int j = 0; j < n_pairs_; ++j)
    for (int t = side_ptr_[2 * j]; t < side_ptr_[2 * j + 1]; ++t)
      for (int u = side_ptr_[2 * j + 1]; u < side_ptr_[2 * j + 2]; ++u)
        position.emplace(lower(side_var_[t], side_var_[u]), 0);
  number_positions(position, hess, hess_row_, hess_col_, hess_map_);
  pair_hess_ptr_.assign(1, 0);
  for (int j = 0; j < n_pairs_; ++j) {
    std::map<int, double> merged;  // unique position -> coefficient
    for (int t = side_ptr_[2 * j]; t < side_ptr_[2 * j + 1]; ++t)
      for (int u = side_ptr_[2 * j + 1]; u < side_ptr_[2 * j + 2]; ++u) {
        const int i = side_var_[t], k = side_var_[u];
        merged[position.at(lower(i, k))] += (i == k ? 2.0 : 1.0) * side_coef_[t] * side_coef_[u];
      }
    for (const auto& [pos, coefficient] : merged) {
      pair_hess_pos_.push_back(pos);
      pair_hess_coef_.push_back(coefficient);
    }
    pair_hess_ptr_.push_back(static_cast<int>(pair_hess_pos_.size()));
  }
}

int MpccLayout::side_single_variable(int s) const {
  const bool single =
      side_ptr_[s + 1] - side_ptr_[s] == 1 && side_coef_[side_ptr_[s]] == 1.0 && side_constant_[s] == 0.0;
  return single ? side_var_[side_ptr_[s]] : -1;
}

SideKey MpccLayout::side_key(int s) const {
  SideKey key;
  for (int t = side_ptr_[s]; t < side_ptr_[s + 1]; ++t) key.first.emplace_back(side_var_[t], side_coef_[t]);
  key.second = side_constant_[s];
  return key;
}

double MpccLayout::side_lower_bound(int s, const Eigen::VectorXd& x_lower, const Eigen::VectorXd& x_upper,
                                    double* magnitude) const {
  return interval_lower(side_var_.data() + side_ptr_[s], side_coef_.data() + side_ptr_[s],
                        side_ptr_[s + 1] - side_ptr_[s], side_constant_[s], x_lower, x_upper, magnitude);
}

std::string MpccLayout::side_name(int s) const {
  return std::string(s % 2 == 0 ? "left" : "right") + " side of " +
         problem_.complementarity_pairs()[static_cast<std::size_t>(s / 2)].name;
}

double MpccLayout::complementarity(const Eigen::Ref<const Eigen::VectorXd>& x, int* worst_pair) const {
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

double MpccLayout::constraint_violation(const Eigen::Ref<const Eigen::VectorXd>& x, std::string* worst) {
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
             : kind == 2 ? side_name(index)
                         : std::string();
  return violation;
}

}  // namespace saltus::timefreezing::detail
