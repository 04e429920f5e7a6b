// Private: the relaxed NLP of a homotopy step as a Reformulation (reformulation.hpp), and the
// relaxations of the pairs as small strategies (solve.hpp, "RELAXATIONS"). A new relaxation is one
// more PairRelaxation here and one more case of make_relaxation.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <saltus/timefreezing/mpcc/solver_options.hpp>
#include <vector>

#include "mpcc_layout.hpp"
#include "reformulation.hpp"

namespace saltus::timefreezing::detail {

/// How a homotopy step at sigma relaxes G_j H_j = 0: product rows with sigma-dependent bounds, or
/// a term of the objective. Stateless apart from what the constructor reads from the problem.
class PairRelaxation {
 public:
  virtual ~PairRelaxation() = default;
  /// Adds the relaxation's rows or term to `nlp` (its structure), for the layout's pairs.
  virtual void shape(Reformulation& nlp, const MpccLayout& layout) const = 0;
  /// Sets the parameters of the rows or term at sigma.
  virtual void set_sigma(double sigma, Reformulation& nlp) const = 0;
  /// The weight w_j of pair j's product in the relaxed Lagrangian at a solution with multipliers
  /// lambda (of all rows; the product rows from first_product_row) at sigma: a product row's
  /// multiplier, or the penalty's rho = 1 / sigma.
  virtual double pair_weight(const Eigen::VectorXd& lambda, int first_product_row, int j, double sigma) const = 0;
};

/// Scholtes: G_j H_j <= sigma for every pair.
/// Smoothing: G_j H_j = sigma for the pairs marked smoothable, <= sigma for the others.
/// Penalty: no rows; the objective gains (1 / sigma) sum_j G_j H_j.
std::unique_ptr<PairRelaxation> make_relaxation(MpccSolverOptions::Relaxation relaxation, const MpccLayout& layout);

/// The relaxed NLP over the Mpcc's variables and bounds:
///   rows [0, m)                  the problem's constraints g,
///   rows [m, m + n_sign)         side(x) >= 0 for the sides that need a row (the affine rows):
///                                not for a side the variable bounds alone keep >= 0
///                                (interval_lower >= 0, up to rounding; e.g. a single variable with
///                                lower bound >= 0, or FESD's sums of step functions alpha in
///                                [0, 1] and n_s - sum alpha), and one row per distinct expression,
///   rows [m + n_sign, m_total)   the relaxation's product rows, one per pair (none under Penalty).
class RelaxedNlp {
 public:
  /// `layout` must outlive this object.
  RelaxedNlp(const MpccLayout& layout, MpccSolverOptions::Relaxation relaxation);

  /// The reformulation (the adapter's data; set_sigma changes its parameters).
  const Reformulation& nlp() const { return nlp_; }
  void set_sigma(double sigma) { relaxation_->set_sigma(sigma, nlp_); }

  int row_count() const { return nlp_.row_count(layout_.constraint_count(), layout_.pair_count()); }
  int sign_row_count() const { return nlp_.affine_row_count(); }
  /// Sign row of side s (counted from m), -1 when the side has none (pruned by its bounds).
  int sign_row_of_side(int s) const { return sign_row_of_side_[static_cast<std::size_t>(s)]; }
  /// PairRelaxation::pair_weight of pair j (lambda of size row_count()).
  double pair_weight(const Eigen::VectorXd& lambda, int j, double sigma) const {
    return relaxation_->pair_weight(lambda, nlp_.first_product_row(layout_.constraint_count()), j, sigma);
  }

 private:
  void add_sign_rows();

  const MpccLayout& layout_;
  std::unique_ptr<PairRelaxation> relaxation_;
  Reformulation nlp_;
  std::vector<int> sign_row_of_side_;
};

}  // namespace saltus::timefreezing::detail
