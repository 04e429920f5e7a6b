#include "branch.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

namespace saltus::timefreezing::detail {

BranchGuess choose_branches(const MpccLayout& layout, const Eigen::Ref<const Eigen::VectorXd>& x,
                            double biactive_threshold, const Eigen::VectorXd* previous, double sigma_ratio) {
  BranchGuess guess;
  guess.zero_side.assign(static_cast<std::size_t>(layout.pair_count()), 0);
  const double shrinking = std::sqrt(sigma_ratio);
  auto ratio = [&](int s) {
    const double before = std::abs(layout.side_value(s, previous->data()));
    return before > 0.0 ? std::abs(layout.side_value(s, x.data())) / before : std::numeric_limits<double>::infinity();
  };
  auto distance = [&](int s) {
    const double v = std::abs(layout.side_value(s, x.data()));
    if (layout.side_norm(s) > 0.0) return v / layout.side_norm(s);
    return v == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
  };
  for (int j = 0; j < layout.pair_count(); ++j) {
    const double dg = distance(2 * j), dh = distance(2 * j + 1);
    int zero = dh < dg ? 1 : 0;
    if (previous != nullptr && previous->size() == layout.variable_count()) {
      const double r_zero = ratio(2 * j + zero), r_other = ratio(2 * j + 1 - zero);
      if (r_zero >= shrinking && r_other < shrinking) {
        zero = 1 - zero;
        ++guess.by_trend;
      }
    }
    guess.zero_side[static_cast<std::size_t>(j)] = zero;
    if (dg < biactive_threshold && dh < biactive_threshold) ++guess.biactive;
  }
  return guess;
}

namespace {

/// Builds a BranchNlp in three passes: the zero sides that bounds can express, the equality rows
/// of the others, the inequality rows of the other sides. A pass stops at the first contradiction
/// (BranchNlp::why).
class BranchBuilder {
 public:
  BranchBuilder(const MpccLayout& layout, const std::vector<int>& zero_side)
      : layout_(layout), zero_side_(zero_side), fixed_(static_cast<std::size_t>(layout.variable_count()), 0) {
    out_.nlp.x_lower = layout.x_lower();
    out_.nlp.x_upper = layout.x_upper();
    out_.nlp.complete_fixed_multipliers = true;
    why_.precision(17);
  }

  BranchNlp build() {
    bool ok = fix_zero_sides();
    ok = ok && add_equality_rows();
    ok = ok && add_inequality_rows();
    if (!ok) out_.why = why_.str();
    return std::move(out_);
  }

 private:
  int zero_of(int j) const { return 2 * j + (zero_side_[static_cast<std::size_t>(j)] != 0 ? 1 : 0); }

  /// Fix x_i = v for side s; false (and why_) when that contradicts an earlier fixing or the bounds.
  bool fix(int i, double v, int s) {
    Eigen::VectorXd& lower = out_.nlp.x_lower;
    Eigen::VectorXd& upper = out_.nlp.x_upper;
    if (fixed_[static_cast<std::size_t>(i)]) {
      if (std::abs(lower[i] - v) <= interval_slack(std::max(1.0, std::abs(v)))) return true;
      why_ << "setting the " << layout_.side_name(s) << " to zero needs " << layout_.problem().variable_name(i) << " = "
           << v << ", another pair's branch fixed it at " << lower[i];
      return false;
    }
    if (v < lower[i] || v > upper[i]) {
      why_ << "setting the " << layout_.side_name(s) << " to zero needs " << layout_.problem().variable_name(i) << " = "
           << v << ", outside its bounds [" << lower[i] << ", " << upper[i] << "]";
      return false;
    }
    fixed_[static_cast<std::size_t>(i)] = 1;
    lower[i] = upper[i] = v;
    ++out_.fixed_variables;
    return true;
  }

  /// Pass 1: zero sides that bounds can express; the others go to row_zero_sides_.
  bool fix_zero_sides() {
    for (int j = 0; j < layout_.pair_count(); ++j) {
      const int s = zero_of(j);
      double magnitude = 0.0;
      const double lower = layout_.side_lower_bound(s, layout_.x_lower(), layout_.x_upper(), &magnitude);
      int nonzero_terms = 0, last = -1;
      for (int t = layout_.side_begin(s); t < layout_.side_end(s); ++t)
        if (layout_.term_coefficient(t) != 0.0) {
          ++nonzero_terms;
          last = t;
        }
      if (std::isfinite(lower) && std::abs(lower) <= interval_slack(magnitude)) {
        for (int t = layout_.side_begin(s); t < layout_.side_end(s); ++t) {
          const double a = layout_.term_coefficient(t);
          const int i = layout_.term_variable(t);
          if (a != 0.0 && !fix(i, a > 0.0 ? layout_.x_lower()[i] : layout_.x_upper()[i], s)) return false;
        }
      } else if (nonzero_terms == 1) {
        const double v = -layout_.side_constant(s) / layout_.term_coefficient(last);
        if (!fix(layout_.term_variable(last), v == 0.0 ? 0.0 : v, s)) return false;  // no -0
      } else if (std::isfinite(lower) && lower > interval_slack(magnitude)) {
        why_ << "the " << layout_.side_name(s) << " is >= " << lower << " > 0 within the bounds";
        return false;
      } else {
        row_zero_sides_.push_back(s);
      }
    }
    return true;
  }

  /// Value of side s if all its variables are fixed (else NaN).
  double fixed_value(int s) const {
    double v = layout_.side_constant(s);
    for (int t = layout_.side_begin(s); t < layout_.side_end(s); ++t) {
      if (layout_.term_coefficient(t) == 0.0) continue;
      if (!fixed_[static_cast<std::size_t>(layout_.term_variable(t))]) return std::numeric_limits<double>::quiet_NaN();
      v += layout_.term_coefficient(t) * out_.nlp.x_lower[layout_.term_variable(t)];
    }
    return v;
  }

  void add_row(int s, bool equality) {
    out_.nlp.affine_side.push_back(s);
    out_.nlp.affine_lower.push_back(0.0);
    out_.nlp.affine_upper.push_back(equality ? 0.0 : std::numeric_limits<double>::infinity());
  }

  /// Pass 2: equality rows, one per distinct expression.
  bool add_equality_rows() {
    for (const int s : row_zero_sides_) {
      const double v = fixed_value(s);
      if (!std::isnan(v)) {
        double magnitude = 0.0;
        layout_.side_lower_bound(s, out_.nlp.x_lower, out_.nlp.x_upper, &magnitude);
        if (std::abs(v) > interval_slack(magnitude)) {
          why_ << "the " << layout_.side_name(s) << " is " << v
               << " != 0 with the variables other pairs' branches fixed";
          return false;
        }
        continue;
      }
      const auto [it, inserted] = equality_row_of_.emplace(layout_.side_key(s), out_.equality_rows);
      if (inserted) {
        add_row(s, true);
        out_.equality_row_other_sides.emplace_back();
        ++out_.equality_rows;
      }
      out_.equality_row_other_sides[static_cast<std::size_t>(it->second)].push_back(s ^ 1);
    }
    return true;
  }

  /// Pass 3: inequality rows for the other sides the branch bounds do not keep >= 0.
  bool add_inequality_rows() {
    std::map<SideKey, int> inequality_row_of;
    for (int j = 0; j < layout_.pair_count(); ++j) {
      const int s = zero_of(j) ^ 1;
      double magnitude = 0.0;
      const double lower = layout_.side_lower_bound(s, out_.nlp.x_lower, out_.nlp.x_upper, &magnitude);
      if (std::isfinite(lower) && lower >= -interval_slack(magnitude)) continue;
      const double v = fixed_value(s);
      if (!std::isnan(v)) {  // all fixed, and the interval says it is negative
        why_ << "the " << layout_.side_name(s) << " is " << v << " < 0 with the variables the branches fixed";
        return false;
      }
      SideKey key = layout_.side_key(s);
      if (equality_row_of_.count(key)) continue;
      if (inequality_row_of.emplace(std::move(key), out_.inequality_rows).second) {
        add_row(s, false);
        ++out_.inequality_rows;
      }
    }
    return true;
  }

  const MpccLayout& layout_;
  const std::vector<int>& zero_side_;
  std::vector<char> fixed_;
  std::vector<int> row_zero_sides_;  ///< zero sides that need an equality row
  std::map<SideKey, int> equality_row_of_;
  std::ostringstream why_;
  BranchNlp out_;
};

}  // namespace

BranchNlp make_branch_nlp(const MpccLayout& layout, const std::vector<int>& zero_side) {
  return BranchBuilder(layout, zero_side).build();
}

Eigen::VectorXd branch_start_multipliers(const BranchNlp& branch, const MpccLayout& layout, const RelaxedNlp& relaxed,
                                         const PrimalDual& from, double sigma) {
  const int m = layout.constraint_count();
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(branch.nlp.row_count(m, layout.pair_count()));
  lambda.head(m) = from.lambda.head(m);
  for (int k = 0; k < branch.nlp.affine_row_count(); ++k) {
    const int s = branch.nlp.affine_side[static_cast<std::size_t>(k)];
    const int sign_row = relaxed.sign_row_of_side(s);
    double mu = sign_row >= 0 ? from.lambda[m + sign_row] : 0.0;
    if (k < branch.equality_rows)
      for (int other : branch.equality_row_other_sides[static_cast<std::size_t>(k)])
        mu += relaxed.pair_weight(from.lambda, other / 2, sigma) * layout.side_value(other, from.x);
    lambda[m + k] = mu;
  }
  return lambda;
}

}  // namespace saltus::timefreezing::detail
