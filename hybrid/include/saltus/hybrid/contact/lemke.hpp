// Exact solver of the planar contact problem (every contact frictionless or with one tangent)
// by Lemke's complementary pivoting.
//
// With one tangent, Coulomb's law is linear complementarity once lambda_t = lambda_t^+ -
// lambda_t^- is split and the slip speed beta is added (Stewart & Trinkle 1996; Anitescu & Potra
// 1997, "Formulating dynamic multi-rigid-body contact problems with friction as solvable linear
// complementarity problems", Nonlinear Dynamics 14). For every contact k, with y = A lambda + b:
//
//   w_n    = y_n                                    _|_  lambda_n    >= 0
//   w^+    = beta + y_t                             _|_  lambda_t^+  >= 0
//   w^-    = beta - y_t                             _|_  lambda_t^-  >= 0
//   w_beta = mu lambda_n - lambda_t^+ - lambda_t^-  _|_  beta        >= 0
//
// (a frictionless contact keeps only its normal row). With one tangent the two directions +-t
// span the friction "cone" exactly, so an LCP solution is an exact solution of the problem.
// Anitescu & Potra show that Lemke's method processes this LCP (it ends at a solution, not on a
// ray) when the problem comes from a mechanical system: A = W M^{-1} W^T, b in the range of W.
//
// The same construction with p unit directions d_i of the tangent plane, lambda_t = sum_i d_i
// beta_i and w_i = beta + d_i . y_t, approximates the friction disk by a p-gon; CoulombSolver
// uses it (detail::PolyhedralContactLcp) to find a starting point when its Newton method stalls.
//
// Lemke's method (Cottle, Pang & Stone, "The Linear Complementarity Problem", 1992, sec. 4.4
// and 4.9) runs with covering vector e = 1 and the lexicographic minimum ratio test, whose
// tie-breaking on the rows of [B^{-1} q, B^{-1}] rules out cycling: redundant contacts (a box
// landing on two or four corners, duplicated tangent rows) make degenerate pivots the rule
// here, not the exception. The final basis is then solved once more directly (polish), and in
// the rare case the result is not accurate, Lemke's method is run again with other tolerances
// and covering vectors (LemkeLcp::solve).
//
// This header declares; the definitions are in lemke.hxx. The library compiles them once for
// the contact bounds 1, 2, 4, 8, 16 and 32 (contact_bound, contact_problem.hpp) and the LCP
// sizes these use (hybrid/src/lemke.cpp); they are declared extern below. For another bound,
// include <saltus/hybrid/contact/lemke.hxx>, which instantiates them on use.
#pragma once

#include <saltus/hybrid/contact/contact_problem.hpp>
#include <saltus/hybrid/vocabulary/errors.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

namespace saltus {

namespace detail {

struct LemkeOptions {
  /// Smallest admissible pivot. Callers scale the LCP so that M and q are O(1) (Jacobi scaling,
  /// ||q||_inf = 1), which makes this relative to the problem scale.
  double pivot_tolerance = 1e-11;
  /// Ratios closer than this (relative) count as ties and go to the lexicographic rule.
  double tie_tolerance = 1e-10;
  /// Pivot budget per LCP variable; past it the solve ends with IterationLimit.
  int max_pivots_per_variable = 50;
  /// Lemke's method is run again with other tolerances when its result is not this accurate:
  /// LemkeSolver judges by the natural-map residual, the polyhedral restarts of CoulombSolver
  /// by the complementarity residual max |min(z, w)| of the scaled LCP (see LemkeLcp::solve).
  double retry_residual = 1e-13;
};

/// Lemke's method for w = M z + q, 0 <= w _|_ z >= 0, n <= MaxN. The caller fills M and q
/// (sized n x n and n), solve() leaves the solution in z. Never allocates.
///
/// Revised form: instead of the tableau B^{-1} [I, -M, -e, q] (n x 2n+2) only B^{-1} and the
/// basic values B^{-1} q are kept, and the entering column is computed when needed. Same
/// arithmetic per pivot (O(n^2)), half the memory, and B^{-1} is exactly what the
/// lexicographic ratio test reads.
template <int MaxN>
class LemkeLcp {
 public:
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, MaxN, MaxN>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MaxN, 1>;

  Matrix M;
  Vector q;
  Vector z;
  int pivots = 0;

  /// Solves, and solves again if the result is not accurate. Ties of the ratio test are
  /// decided up to a tolerance: too tight a one lets round-off break a tie instead of the
  /// lexicographic rule (cycling, or a ray that is not there), too loose a one takes a near-tie
  /// that is none (a slightly infeasible basis); the pivot tolerance may admit a tiny pivot
  /// that ruins the basis of a nearly singular problem. Both are rare and show in the
  /// residual, so other tolerances are tried while it is above options.retry_residual, and
  /// last other covering vectors, which take another path through the bases. `pivots` counts
  /// all attempts.
  ContactSolveStatus solve(const LemkeOptions& options);

  /// The same, judging each attempt by score(z) (lower is better) instead of the residual.
  /// A member template: calling it needs lemke.hxx.
  template <class Score>
  ContactSolveStatus solve(const LemkeOptions& options, Score&& score);

  /// One run of Lemke's method with the given tolerances. Covering vector: e = 1 (covering
  /// 0), or a fixed pattern of entries in [0.5, 1.5] (covering 1, 2).
  ContactSolveStatus solve_once(const LemkeOptions& options, int covering = 0);

  /// max_i |min(z_i, (M z + q)_i)|: zero exactly at a solution.
  double residual(const Vector& x);

 private:
  // d = B^{-1} a_v, with a_v the column of variable v in [I, -M, -e].
  void column(int v);

  // The value of z0 if it is basic, else 0.
  double z0_value(int z0) const;

  // Gauss-Jordan pivot of [B^{-1}, x] on row r for the entering column d.
  void pivot(int r);

  // Lexicographic minimum ratio test on the rows of [x, B^{-1}] / d (Cottle-Pang-Stone 4.9):
  // keeps the rows that tie on the current column, moves to the next column while more than
  // one is left. z0 leaves as soon as it ties on x, which ends the method. Returns -1 on a ray.
  int ratio_test(int z0, const LemkeOptions& options);

  // B^{-1} has accumulated one rounding error per pivot, but the final basis is exact
  // information: with Z its basic z-unknowns, w_Z = 0 and z_i = 0 off Z, so M_ZZ z_Z = -q_Z.
  // Solving that system directly (plus one step of iterative refinement) gives the basic
  // solution to the accuracy of one LU; it is kept if its complementarity residual is smaller.
  void polish();

  // zp = the solution with w_i = 0 for i in cand_[0..nz) and z_i = 0 elsewhere.
  bool solve_on(int nz);

  // LU with partial pivoting of the leading k x k block of Binv_, in place.
  bool factorize(int k);

  // Solves (LU) x = P v in place, with the factors of factorize(k).
  void substitute(int k, Vector& v) const;

  Matrix Binv_;
  Vector x_, d_, e_, w_, zp_, rz_, sz_, zbest_;
  std::array<int, MaxN> perm_{};
  Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, MaxN> prow_;
  std::array<int, MaxN> basis_{};
  std::array<int, MaxN> cand_{};
};

/// The contact problem as an LCP with a polyhedral friction cone: a contact with one tangent
/// gets the two directions +-t (exact), one with two tangents `spatial_directions` directions
/// at equal angles (inscribed polygon), a frictionless one (no tangent or mu = 0) none.
/// Unknowns per contact: [lambda_n, beta_1..beta_p, beta] as in the header comment.
template <int MaxContacts, int MaxDirections>
class PolyhedralContactLcp {
 public:
  static constexpr int max_unknowns = MaxContacts * (MaxDirections + 2);
  using Problem = ContactProblem<MaxContacts>;
  using Vector = typename Problem::Vector;

  LemkeLcp<max_unknowns> lcp;

  /// Builds and solves the LCP; lambda (size p.rows()) is the solution as contact forces.
  /// The polygon's first direction is at angle `rotation` from the first tangent. When
  /// `exact` (every polygon exact: planar contacts), the attempts of LemkeLcp::solve are
  /// judged by the natural-map residual of the contact problem itself.
  ContactSolveStatus solve(const Problem& p, int spatial_directions, const LemkeOptions& options,
                           Vector& lambda, double rotation = 0.0, bool exact = false);

 private:
  // Each LCP unknown j is a combination of at most two components of lambda,
  // lambda[row_[j][a]] += coef_[j][a] z_j (none for beta), which includes the symmetric
  // Jacobi scaling lambda = d_k lambda', y' = d_k y with d_k = 1/sqrt(mean diagonal of A_kk);
  // q is then normalised to ||q||_inf = 1. The LCP's entries are O(1) whatever the units and
  // the mass ratios, so that absolute pivot and tie tolerances work. Scaling a contact's
  // normal and tangential unknowns alike keeps the unit and mu coefficients of the beta rows.
  void build(const Problem& p, int spatial_directions, double rotation);

  void set(int j, int r0, double c0, int r1, double c1) {
    row_[j] = {r0, r1};
    coef_[j] = {c0, c1};
  }

  // lambda (size m) from the LCP unknowns z.
  template <class Z>
  void to_forces(const Z& z, int m, Vector& lambda) const;

  double qscale_ = 1.0;
  std::array<int, MaxContacts> first_{}, dirs_{};
  std::array<std::array<int, 2>, max_unknowns> row_{};
  std::array<std::array<double, 2>, max_unknowns> coef_{};
  Vector y_;
};

/// Stands in for PolyhedralContactLcp where MaxContacts is too large for its storage.
template <int MaxContacts>
struct NoPolyhedralLcp {
  template <class Vector>
  ContactSolveStatus solve(const ContactProblem<MaxContacts>& p, int, const LemkeOptions&,
                           Vector& lambda, double = 0.0) {
    lambda.setConstant(p.rows(), std::numeric_limits<double>::quiet_NaN());
    return ContactSolveStatus::NoSolution;
  }
};

}  // namespace detail

/// Lemke's method on the exact LCP of a planar contact problem (every contact frictionless or
/// with one tangent), MaxContacts contacts at most; see the header comment.
template <int MaxContacts>
class LemkeSolver {
  static_assert(4 * MaxContacts <= 128,
                "LemkeSolver: the LCP (4 unknowns per contact) would exceed Eigen's limit for "
                "fixed-size storage (128 x 128 doubles)");

 public:
  using Problem = ContactProblem<MaxContacts>;
  using Solution = ContactSolution<MaxContacts>;
  using Vector = typename Problem::Vector;
  using Options = detail::LemkeOptions;

  LemkeSolver() = default;
  explicit LemkeSolver(const Options& o) : options(o) {}

  Options options;

  /// Solves p into out (lambda, y = A lambda + b, natural-map residual, pivots as iterations).
  /// Throws InvalidArgument for a spatial contact (2 tangents), a negative or non-finite mu,
  /// or A and b not sized or not finite as the contacts declare.
  ContactSolveStatus solve(const Problem& p, Solution& out);

 private:
  static void validate(const Problem& p);

  detail::PolyhedralContactLcp<MaxContacts, 2> lcp_;
};

// Compiled once in the library (hybrid/src/lemke.cpp) for the contact bounds 1, 2, 4, 8, 16, 32
// (contact_bound). The LCP sizes: 4 B unknowns for LemkeSolver<B> (4, 8, 16, 32, 64, 128), and
// B (s + 2) for the polygon restarts of CoulombSolver<B> with s sides (coulomb_solver.hpp:
// 1 x 14, 2 x 14, 4 x 14, 8 x 8, 16 x 6).
#ifndef SALTUS_CONTACT_NO_EXTERN_TEMPLATES
extern template class detail::LemkeLcp<4>;
extern template class detail::LemkeLcp<8>;
extern template class detail::LemkeLcp<14>;
extern template class detail::LemkeLcp<16>;
extern template class detail::LemkeLcp<28>;
extern template class detail::LemkeLcp<32>;
extern template class detail::LemkeLcp<56>;
extern template class detail::LemkeLcp<64>;
extern template class detail::LemkeLcp<96>;
extern template class detail::LemkeLcp<128>;
extern template class detail::PolyhedralContactLcp<1, 2>;
extern template class detail::PolyhedralContactLcp<2, 2>;
extern template class detail::PolyhedralContactLcp<4, 2>;
extern template class detail::PolyhedralContactLcp<8, 2>;
extern template class detail::PolyhedralContactLcp<16, 2>;
extern template class detail::PolyhedralContactLcp<32, 2>;
extern template class LemkeSolver<1>;
extern template class LemkeSolver<2>;
extern template class LemkeSolver<4>;
extern template class LemkeSolver<8>;
extern template class LemkeSolver<16>;
extern template class LemkeSolver<32>;
#endif

}  // namespace saltus
