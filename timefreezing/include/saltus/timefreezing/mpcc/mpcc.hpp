// The mathematical program with complementarity constraints (MPCC) that the time-freezing
// discretisation hands to the solver, as an abstract interface with exact sparse derivatives:
//
//     min_x  f(x)
//     s.t.   g_lower <= g(x) <= g_upper,          x_lower <= x <= x_upper,
//            0 <= G_k(x)  _|_  H_k(x) >= 0,        k = 1..n_pairs,
//
// where f and g are twice continuously differentiable and every complementarity side G_k, H_k is
// AFFINE in x (FESD's pairs are: a multiplier against a step function, a multiplier against one
// minus a step function, and sums of those over a finite element (cross-complementarity); all
// affine). Keeping the sides affine lets the solver relax or penalise the pairs generically
// (mpcc_solver.hpp): the product G_k H_k has the gradient G_k a_H + H_k a_G and the constant
// Hessian a_G a_H' + a_H a_G', with no help from the problem.
//
// Sparse structures are lists of (row, column) entries. Entries may repeat: values at the same
// position are added (the solver merges them once, when it first sees the structure). The Hessian
// structure lists the LOWER triangle only (row >= column); an off-diagonal entry stands for both
// symmetric positions, once.
#pragma once

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

/// One entry of a sparse structure: (row, column), 0-based.
struct SparseEntry {
  int row = 0;
  int col = 0;
};

/// An affine function a' x + b of the NLP variables, stored sparsely: one side of a
/// complementarity pair. Each variable index appears at most once in `terms`.
struct AffineExpression {
  std::vector<std::pair<int, double>> terms;  ///< (variable index, coefficient a_i)
  double constant = 0.0;                      ///< b

  double value(const Eigen::Ref<const Eigen::VectorXd>& x) const {
    double s = constant;
    for (const auto& [i, a] : terms) s += a * x[i];
    return s;
  }
  /// The expression is the single variable x_i (coefficient 1, constant 0); returns i or -1.
  int single_variable() const {
    return (terms.size() == 1 && terms[0].second == 1.0 && constant == 0.0) ? terms[0].first : -1;
  }
};

/// 0 <= left(x) _|_ right(x) >= 0, named for messages ("lambda_n[3] _|_ alpha[3]").
struct ComplementarityPair {
  AffineExpression left;
  AffineExpression right;
  std::string name;
  /// The equality G H = sigma is a well-posed smoothing of this pair: under the solver's
  /// Relaxation::Smoothing its relaxed row is G H = sigma instead of G H <= sigma. Set it where the
  /// equalities determine the sides given the rest of the problem: a stage's step function alpha
  /// and its multipliers (c = lambda_p - lambda_n given, lambda_n alpha = sigma and
  /// lambda_p (1 - alpha) = sigma have exactly one solution with alpha in (0, 1), a smooth sigmoid
  /// alpha(c)); never on pairs whose equalities would over-determine the sides (FESD's
  /// cross-complementarity: one element's sum of step functions against several points'
  /// multipliers).
  bool smoothable = false;
};

/// An MPCC with exact first and second derivatives (sizes: n variables, m constraints).
/// Implementations are immutable after construction: every method is const and may be called in
/// any order; x always has size n, multipliers size m.
class Mpcc {
 public:
  virtual ~Mpcc() = default;

  virtual int variable_count() const = 0;    ///< n
  virtual int constraint_count() const = 0;  ///< m (equalities have g_lower == g_upper)

  /// Bounds (use +-infinity for none); sizes n, n, m, m.
  virtual void bounds(Eigen::Ref<Eigen::VectorXd> x_lower, Eigen::Ref<Eigen::VectorXd> x_upper,
                      Eigen::Ref<Eigen::VectorXd> g_lower, Eigen::Ref<Eigen::VectorXd> g_upper) const = 0;
  /// The starting point of the first homotopy step (size n).
  virtual void initial_point(Eigen::Ref<Eigen::VectorXd> x) const = 0;

  virtual double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const = 0;
  virtual void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::VectorXd> gradient) const = 0;
  virtual void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const = 0;

  /// Structure of dg/dx (m x n); fixed for the life of the object.
  virtual const std::vector<SparseEntry>& jacobian_structure() const = 0;
  /// Values in the order of jacobian_structure().
  virtual void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> values) const = 0;

  /// Structure of the Hessian of the Lagrangian (n x n, lower triangle); fixed.
  virtual const std::vector<SparseEntry>& hessian_structure() const = 0;
  /// Values of objective_factor * d2f/dx2 + sum_j multipliers_j d2g_j/dx2, in the order of
  /// hessian_structure().
  virtual void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double objective_factor,
                              const Eigen::Ref<const Eigen::VectorXd>& multipliers,
                              Eigen::Ref<Eigen::VectorXd> values) const = 0;

  /// The complementarity pairs (affine sides); empty for a plain NLP.
  virtual const std::vector<ComplementarityPair>& complementarity_pairs() const = 0;

  /// Names for messages and reports.
  virtual std::string variable_name(int i) const { return "x[" + std::to_string(i) + "]"; }
  virtual std::string constraint_name(int j) const { return "g[" + std::to_string(j) + "]"; }
};

}  // namespace saltus::timefreezing
