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
  ContactSolveStatus solve(const LemkeOptions& options) {
    return solve(options, [this](const Vector& x) { return residual(x); });
  }

  /// The same, judging each attempt by score(z) (lower is better) instead of the residual.
  template <class Score>
  ContactSolveStatus solve(const LemkeOptions& options, Score&& score) {
    // tie factor, pivot factor, covering vector (0: ones)
    static constexpr std::array<std::array<double, 3>, 7> attempts{{{1.0, 1.0, 0},
                                                                    {1e-2, 1e2, 0},
                                                                    {1e2, 1e2, 0},
                                                                    {1e-4, 1e-2, 0},
                                                                    {1e2, 1e4, 0},
                                                                    {1.0, 1.0, 1},
                                                                    {1.0, 1.0, 2}}};
    int total = 0;
    ContactSolveStatus best = ContactSolveStatus::IterationLimit;
    double best_residual = 0.0;
    for (std::size_t a = 0; a < attempts.size(); ++a) {
      LemkeOptions o = options;
      o.tie_tolerance *= attempts[a][0];
      o.pivot_tolerance *= attempts[a][1];
      const ContactSolveStatus status = solve_once(o, static_cast<int>(attempts[a][2]));
      total += pivots;
      const double res = score(z);
      const bool solved = status == ContactSolveStatus::Solved;
      const bool best_solved = best == ContactSolveStatus::Solved;
      if (a == 0 || (solved && !best_solved) || (solved == best_solved && res < best_residual)) {
        best = status;
        best_residual = res;
        zbest_ = z;
      }
      if (best == ContactSolveStatus::Solved && best_residual <= options.retry_residual) break;
    }
    z = zbest_;
    pivots = total;
    return best;
  }

  /// One run of Lemke's method with the given tolerances. Covering vector: e = 1 (covering
  /// 0), or a fixed pattern of entries in [0.5, 1.5] (covering 1, 2).
  ContactSolveStatus solve_once(const LemkeOptions& options, int covering = 0) {
    const int n = static_cast<int>(q.size());
    pivots = 0;
    z.setZero(n);
    if (n == 0 || q.minCoeff() >= 0.0) return ContactSolveStatus::Solved;
    const int max_pivots = options.max_pivots_per_variable * n;
    e_.resize(n);
    for (int i = 0; i < n; ++i)
      e_[i] = covering == 0 ? 1.0 : 1.0 + 0.5 * std::sin(1.7 * covering * (i + 1));

    // Variables: w_i = i, z_i = n + i, z0 = 2n. Initial basis: all w, B = I.
    const int z0 = 2 * n;
    Binv_.setIdentity(n, n);
    x_ = q;
    for (int i = 0; i < n; ++i) basis_[i] = i;

    // First pivot: z0 enters at the most negative q_i / e_i. Among ties the largest index is
    // the one that leaves every row of [q, B^{-1}] lexicographically positive.
    const double qmin = q.cwiseQuotient(e_).minCoeff();
    int r = 0;
    for (int i = 0; i < n; ++i)
      if (q[i] / e_[i] <= qmin + options.tie_tolerance * (1.0 + std::abs(qmin))) r = i;
    column(z0);
    pivot(r);
    int leaving = basis_[r];
    basis_[r] = z0;
    int entering = leaving + n;  // the complement of w_r

    ContactSolveStatus status = ContactSolveStatus::IterationLimit;
    while (pivots < max_pivots) {
      column(entering);
      r = ratio_test(z0, options);
      if (r < 0) {
        // A ray, unless z0 is basic at zero: the current almost-complementary point is then
        // complementary (a degenerate end that the ratio test missed by round-off).
        status = z0_value(z0) <= options.pivot_tolerance ? ContactSolveStatus::Solved
                                                         : ContactSolveStatus::NoSolution;
        break;
      }
      leaving = basis_[r];
      pivot(r);
      basis_[r] = entering;
      if (leaving == z0) {
        status = ContactSolveStatus::Solved;
        break;
      }
      entering = leaving < n ? leaving + n : leaving - n;
    }

    for (int i = 0; i < n; ++i)
      if (basis_[i] >= n && basis_[i] < 2 * n) z[basis_[i] - n] = x_[i];
    if (status == ContactSolveStatus::Solved) polish();
    return status;
  }

  /// max_i |min(z_i, (M z + q)_i)|: zero exactly at a solution.
  double residual(const Vector& x) {
    w_.noalias() = M * x;
    w_ += q;
    return w_.cwiseMin(x).cwiseAbs().maxCoeff();
  }

 private:
  // d = B^{-1} a_v, with a_v the column of variable v in [I, -M, -e].
  void column(int v) {
    const int n = static_cast<int>(q.size());
    if (v < n) {
      d_ = Binv_.col(v);
    } else if (v < 2 * n) {
      d_.noalias() = Binv_ * M.col(v - n);
      d_ = -d_;
    } else {
      d_.noalias() = Binv_ * e_;
      d_ = -d_;
    }
  }

  double z0_value(int z0) const {
    for (int i = 0; i < static_cast<int>(q.size()); ++i)
      if (basis_[i] == z0) return x_[i];
    return 0.0;
  }

  // Gauss-Jordan pivot of [B^{-1}, x] on row r for the entering column d.
  void pivot(int r) {
    ++pivots;
    const double inv = 1.0 / d_[r];
    Binv_.row(r) *= inv;
    x_[r] *= inv;
    prow_ = Binv_.row(r);
    d_[r] = 0.0;
    Binv_.noalias() -= d_ * prow_;
    x_ -= x_[r] * d_;
  }

  // Lexicographic minimum ratio test on the rows of [x, B^{-1}] / d (Cottle-Pang-Stone 4.9):
  // keeps the rows that tie on the current column, moves to the next column while more than
  // one is left. z0 leaves as soon as it ties on x, which ends the method. Returns -1 on a ray.
  int ratio_test(int z0, const LemkeOptions& options) {
    const int n = static_cast<int>(q.size());
    int count = 0;
    for (int i = 0; i < n; ++i)
      if (d_[i] > options.pivot_tolerance) cand_[count++] = i;
    if (count == 0) return -1;
    // Basic values are nonnegative in exact arithmetic; read a degenerate one that round-off
    // made -1e-17 as 0, lest it give the smallest (negative) ratio through a tiny d_i.
    auto entry = [&](int i, int c) { return c < 0 ? std::max(x_[i], 0.0) : Binv_(i, c); };
    for (int c = -1; c < n && count > 1; ++c) {
      double best = 0.0;
      for (int a = 0; a < count; ++a) {
        const int i = cand_[a];
        const double ratio = entry(i, c) / d_[i];
        if (a == 0 || ratio < best) best = ratio;
      }
      const double tol = options.tie_tolerance * (1.0 + std::abs(best));
      int kept = 0;
      for (int a = 0; a < count; ++a) {
        const int i = cand_[a];
        if (entry(i, c) / d_[i] <= best + tol) cand_[kept++] = i;
      }
      count = kept;
      if (c < 0)
        for (int a = 0; a < count; ++a)
          if (basis_[cand_[a]] == z0) return cand_[a];
    }
    return cand_[0];
  }

  // B^{-1} has accumulated one rounding error per pivot, but the final basis is exact
  // information: with Z its basic z-unknowns, w_Z = 0 and z_i = 0 off Z, so M_ZZ z_Z = -q_Z.
  // Solving that system directly (plus one step of iterative refinement) gives the basic
  // solution to the accuracy of one LU; it is kept if its complementarity residual is smaller.
  void polish() {
    const int n = static_cast<int>(q.size());
    int nz = 0;
    for (int i = 0; i < n; ++i)
      if (basis_[i] >= n && basis_[i] < 2 * n) cand_[nz++] = basis_[i] - n;
    if (solve_on(nz) && residual(zp_) <= residual(z)) z = zp_;
  }

  // zp = the solution with w_i = 0 for i in cand_[0..nz) and z_i = 0 elsewhere.
  bool solve_on(int nz) {
    const int n = static_cast<int>(q.size());
    zp_.setZero(n);
    if (nz == 0) return true;
    // M_ZZ is factorised in place in B^{-1}'s storage, no longer needed: a second n x n
    // matrix for an LU object would double the solver's size.
    rz_.resize(nz);
    for (int a = 0; a < nz; ++a) {
      for (int c = 0; c < nz; ++c) Binv_(a, c) = M(cand_[a], cand_[c]);
      rz_[a] = -q[cand_[a]];
    }
    if (!factorize(nz)) return false;
    sz_ = rz_;
    substitute(nz, sz_);
    for (int a = 0; a < nz; ++a) {  // one step of iterative refinement
      double s = -q[cand_[a]];
      for (int c = 0; c < nz; ++c) s -= M(cand_[a], cand_[c]) * sz_[c];
      rz_[a] = s;
    }
    substitute(nz, rz_);
    sz_ += rz_;
    if (!sz_.allFinite()) return false;
    // Values are nonnegative in exact arithmetic; a degenerate one can come out -1e-17.
    for (int a = 0; a < nz; ++a) zp_[cand_[a]] = std::max(sz_[a], 0.0);
    return true;
  }

  // LU with partial pivoting of the leading k x k block of Binv_, in place.
  bool factorize(int k) {
    for (int j = 0; j < k; ++j) {
      int pr = j;
      for (int i = j + 1; i < k; ++i)
        if (std::abs(Binv_(i, j)) > std::abs(Binv_(pr, j))) pr = i;
      perm_[j] = pr;
      if (!(std::abs(Binv_(pr, j)) > 0.0)) return false;
      if (pr != j) Binv_.row(j).head(k).swap(Binv_.row(pr).head(k));
      const double inv = 1.0 / Binv_(j, j);
      for (int i = j + 1; i < k; ++i) {
        const double l = Binv_(i, j) *= inv;
        for (int c = j + 1; c < k; ++c) Binv_(i, c) -= l * Binv_(j, c);
      }
    }
    return true;
  }

  // Solves (LU) x = P v in place, with the factors of factorize(k).
  void substitute(int k, Vector& v) const {
    for (int j = 0; j < k; ++j) std::swap(v[j], v[perm_[j]]);
    for (int i = 0; i < k; ++i)
      for (int c = 0; c < i; ++c) v[i] -= Binv_(i, c) * v[c];
    for (int i = k - 1; i >= 0; --i) {
      for (int c = i + 1; c < k; ++c) v[i] -= Binv_(i, c) * v[c];
      v[i] /= Binv_(i, i);
    }
  }

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
                           Vector& lambda, double rotation = 0.0, bool exact = false) {
    build(p, std::min(spatial_directions, MaxDirections), rotation);
    ContactSolveStatus status;
    if (exact) {
      status = lcp.solve(options, [&](const auto& z) {
        to_forces(z, p.rows(), lambda);
        y_.noalias() = p.A * lambda;
        y_ += p.b;
        return natural_map_residual(p, lambda, y_);
      });
    } else {
      status = lcp.solve(options);
    }
    to_forces(lcp.z, p.rows(), lambda);
    return status;
  }

 private:
  // Each LCP unknown j is a combination of at most two components of lambda,
  // lambda[row_[j][a]] += coef_[j][a] z_j (none for beta), which includes the symmetric
  // Jacobi scaling lambda = d_k lambda', y' = d_k y with d_k = 1/sqrt(mean diagonal of A_kk);
  // q is then normalised to ||q||_inf = 1. The LCP's entries are O(1) whatever the units and
  // the mass ratios, so that absolute pivot and tie tolerances work. Scaling a contact's
  // normal and tangential unknowns alike keeps the unit and mu coefficients of the beta rows.
  void build(const Problem& p, int spatial_directions, double rotation) {
    const double global = contact_problem_scale(p);  // m / trace(A)
    int n = 0;
    for (int k = 0; k < p.contacts; ++k) {
      const int r = p.row[k], nt = p.tangents[k], nk = 1 + nt;
      const double a = p.A.diagonal().segment(r, nk).cwiseAbs().sum() / nk;
      const double d = 1.0 / std::sqrt(a > 0.0 ? a : 1.0 / global);
      const int dirs = nt == 0 || !(p.mu[k] > 0.0) ? 0 : nt == 1 ? 2 : spatial_directions;
      first_[k] = n;
      dirs_[k] = dirs;
      set(n++, r, d, r, 0.0);
      for (int i = 0; i < dirs; ++i) {
        if (nt == 1) {
          set(n++, r + 1, i == 0 ? d : -d, r + 1, 0.0);
        } else {
          const double th = rotation + 2.0 * 3.14159265358979323846 * i / dirs;
          set(n++, r + 1, d * std::cos(th), r + 2, d * std::sin(th));
        }
      }
      if (dirs > 0) set(n++, r, 0.0, r, 0.0);  // beta, the slip speed: no part of lambda
    }
    lcp.M.resize(n, n);
    lcp.q.resize(n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        double v = 0.0;
        for (int a = 0; a < 2; ++a)
          for (int c = 0; c < 2; ++c) v += coef_[i][a] * coef_[j][c] * p.A(row_[i][a], row_[j][c]);
        lcp.M(i, j) = v;
      }
      lcp.q[i] = coef_[i][0] * p.b[row_[i][0]] + coef_[i][1] * p.b[row_[i][1]];
    }
    for (int k = 0; k < p.contacts; ++k) {
      const int dirs = dirs_[k];
      if (dirs == 0) continue;
      const int normal = first_[k], slip = normal + dirs + 1;
      lcp.M(slip, normal) = p.mu[k];
      for (int i = 1; i <= dirs; ++i) {
        lcp.M(normal + i, slip) = 1.0;
        lcp.M(slip, normal + i) = -1.0;
      }
    }
    qscale_ = lcp.q.cwiseAbs().maxCoeff();
    if (!(qscale_ > 0.0)) qscale_ = 1.0;
    lcp.q /= qscale_;
  }

  void set(int j, int r0, double c0, int r1, double c1) {
    row_[j] = {r0, r1};
    coef_[j] = {c0, c1};
  }

  template <class Z>
  void to_forces(const Z& z, int m, Vector& lambda) const {
    lambda.setZero(m);
    for (int j = 0; j < static_cast<int>(z.size()); ++j)
      for (int a = 0; a < 2; ++a) lambda[row_[j][a]] += qscale_ * coef_[j][a] * z[j];
  }

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

  ContactSolveStatus solve(const Problem& p, Solution& out) {
    validate(p);
    const int m = p.rows();
    out.lambda.setZero(m);
    out.iterations = 0;
    out.status = ContactSolveStatus::Solved;

    // lambda = 0 solves the problem as soon as no contact is approaching: the friction radius
    // mu lambda_n is then 0, whatever the tangential velocity (a wider test than q >= 0, which
    // would also demand b_t = 0).
    bool trivial = true;
    for (int k = 0; k < p.contacts; ++k) trivial = trivial && p.b[p.row[k]] >= 0.0;
    if (trivial) {
      out.y = p.b;
      out.residual = natural_map_residual(p, out.lambda, out.y);
      return out.status;
    }

    out.status = lcp_.solve(p, 2, options, out.lambda, 0.0, true);
    out.iterations = lcp_.lcp.pivots;
    out.y.noalias() = p.A * out.lambda;
    out.y += p.b;
    out.residual = natural_map_residual(p, out.lambda, out.y);
    return out.status;
  }

 private:
  static void validate(const Problem& p) {
    SALTUS_DEMAND(p.contacts >= 0 && p.contacts <= MaxContacts, InvalidArgument,
                  "LemkeSolver: ", p.contacts, " contacts, at most ", MaxContacts);
    for (int k = 0; k < p.contacts; ++k) {
      SALTUS_DEMAND(p.tangents[k] >= 0 && p.tangents[k] <= 1, InvalidArgument,
                    "LemkeSolver: contact ", k, " has ", p.tangents[k],
                    " tangents; Lemke solves planar problems only (0 or 1 tangent), use "
                    "CoulombSolver for spatial friction");
      SALTUS_DEMAND(std::isfinite(p.mu[k]) && p.mu[k] >= 0.0, InvalidArgument,
                    "LemkeSolver: contact ", k, " has friction coefficient mu = ", p.mu[k]);
    }
    const int m = p.rows();
    SALTUS_DEMAND(p.A.rows() == m && p.A.cols() == m && p.b.size() == m, InvalidArgument,
                  "LemkeSolver: A is ", p.A.rows(), "x", p.A.cols(), " and b has ", p.b.size(),
                  " rows, the contacts declare ", m);
    SALTUS_DEMAND(p.A.allFinite() && p.b.allFinite(), InvalidArgument,
                  "LemkeSolver: A or b is not finite");
  }

  detail::PolyhedralContactLcp<MaxContacts, 2> lcp_;
};

}  // namespace saltus
