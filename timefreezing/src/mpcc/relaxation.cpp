#include "relaxation.hpp"

#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <utility>

namespace saltus::timefreezing::detail {

namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

/// Product rows -inf <= G_j H_j <= sigma, or sigma <= G_j H_j <= sigma where `equality` is set.
class ProductRows : public PairRelaxation {
 public:
  explicit ProductRows(std::vector<char> equality) : equality_(std::move(equality)) {}
  void shape(Reformulation& nlp, const MpccLayout& layout) const override {
    nlp.product_rows = true;
    nlp.product_lower.assign(static_cast<std::size_t>(layout.pair_count()), -inf);
    nlp.product_upper.assign(static_cast<std::size_t>(layout.pair_count()), inf);
  }
  void set_sigma(double sigma, Reformulation& nlp) const override {
    for (std::size_t j = 0; j < equality_.size(); ++j) {
      nlp.product_lower[j] = equality_[j] ? sigma : -inf;
      nlp.product_upper[j] = sigma;
    }
  }
  double pair_weight(const Eigen::VectorXd& lambda, int first_product_row, int j, double) const override {
    return lambda[first_product_row + j];
  }

 private:
  std::vector<char> equality_;  ///< per pair
};

/// rho sum_j G_j H_j in the objective, rho = 1 / sigma.
class ProductPenalty : public PairRelaxation {
 public:
  void shape(Reformulation& nlp, const MpccLayout&) const override { nlp.penalty = true; }
  void set_sigma(double sigma, Reformulation& nlp) const override { nlp.penalty_sigma = sigma; }
  double pair_weight(const Eigen::VectorXd&, int, int, double sigma) const override { return 1.0 / sigma; }
};

}  // namespace

std::unique_ptr<PairRelaxation> make_relaxation(MpccSolverOptions::Relaxation relaxation, const MpccLayout& layout) {
  const std::vector<ComplementarityPair>& pairs = layout.problem().complementarity_pairs();
  std::vector<char> equality(pairs.size(), 0);
  switch (relaxation) {
    case MpccSolverOptions::Relaxation::Penalty:
      return std::make_unique<ProductPenalty>();
    case MpccSolverOptions::Relaxation::Smoothing:
      for (std::size_t j = 0; j < pairs.size(); ++j) equality[j] = pairs[j].smoothable ? 1 : 0;
      break;
    case MpccSolverOptions::Relaxation::Scholtes:
      break;
  }
  return std::make_unique<ProductRows>(std::move(equality));
}

RelaxedNlp::RelaxedNlp(const MpccLayout& layout, MpccSolverOptions::Relaxation relaxation)
    : layout_(layout), relaxation_(make_relaxation(relaxation, layout)) {
  nlp_.x_lower = layout.x_lower();
  nlp_.x_upper = layout.x_upper();
  add_sign_rows();
  relaxation_->shape(nlp_, layout);
  relaxation_->set_sigma(1.0, nlp_);
}

void RelaxedNlp::add_sign_rows() {
  // One per distinct side that its bounds do not already keep >= 0. Row pruning: the interval
  // bound of the side over the variable bounds (the single variable with lower bound >= 0 is its
  // simplest case). With bound_relax_factor = 0 Ipopt keeps the bounds exactly, so the side stays
  // >= 0 (up to the rounding allowed by interval_slack).
  std::map<SideKey, int> row_of_side;
  const int sides = 2 * layout_.pair_count();
  sign_row_of_side_.assign(static_cast<std::size_t>(sides), -1);
  for (int s = 0; s < sides; ++s) {
    const int single = layout_.side_single_variable(s);
    if (single >= 0 && layout_.x_lower()[single] >= 0.0) continue;
    double magnitude = 0.0;
    const double lower = layout_.side_lower_bound(s, layout_.x_lower(), layout_.x_upper(), &magnitude);
    if (std::isfinite(lower) && lower >= -interval_slack(magnitude)) continue;
    const auto [it, inserted] = row_of_side.emplace(layout_.side_key(s), nlp_.affine_row_count());
    if (inserted) {
      nlp_.affine_side.push_back(s);
      nlp_.affine_lower.push_back(0.0);
      nlp_.affine_upper.push_back(inf);
    }
    sign_row_of_side_[static_cast<std::size_t>(s)] = it->second;
  }
}

}  // namespace saltus::timefreezing::detail
