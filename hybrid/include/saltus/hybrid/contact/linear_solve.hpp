// Linear solves for any scalar type by factorising the double value only.
//
// The flows, guards and jump maps are templates on the scalar type T (double, or nested dual
// numbers carrying derivatives). Every linear system they solve, A(T) x = b(T), is solved with
// the factorisation of the real part A0 = value(A) alone:
//     x <- A0^{-1} (b - (A - A0) x),   repeated order(T) + 1 times from x = 0.
// A - A0 has no real part, so its (order + 1)-th power vanishes in dual arithmetic and the
// iteration ends exactly at x = A^{-1} b with all its derivatives (a terminating Neumann series;
// for T = double it is one solve). Derivatives therefore reuse the factorisation of the value
// computation, and no matrix decomposition is ever instantiated on dual numbers (which would cost
// minutes of compile time per scene).
//
// MinNormSolver factorises A0 with a complete orthogonal decomposition and returns the
// minimum-norm least-squares solution when A0 is rank deficient (redundant contacts).
//
// Derivatives of a minimum-norm solution (MinNormSolve). When A0 is rank deficient, the series
// above does not give the derivative of x = A^+ b: it misses how the row space of A turns. Saltus
// needs that derivative whenever the split of a load between redundant contacts matters, e.g.
// the friction of a box sliding on four corners depends on how its weight is shared. For the
// consistent systems that arise (b in the range of A, constant rank), x = A^T y for ANY solution y
// of the Gram system (A A^T) y = b, since two solutions differ by a vector A^T annihilates. So x
// is differentiated through y: y = y0 + corrections from the same terminating series on
// G = A A^T, whose value G0 is factorised once. The value of x itself is taken from the complete
// orthogonal decomposition of A0 (the Gram form squares the condition number and is only used
// for the derivative parts).
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <type_traits>
#include <utility>

namespace saltus {

namespace ad {
/// Real part of a matrix of possibly dual entries.
template <class Derived, class Out>
void value_into(const Eigen::MatrixBase<Derived>& m, Out& out) {
  out.resize(m.rows(), m.cols());
  for (Eigen::Index j = 0; j < m.cols(); ++j)
    for (Eigen::Index i = 0; i < m.rows(); ++i) out(i, j) = value_of(m(i, j));
}
}  // namespace ad

/// Relative rank threshold of the Delassus solves: singular values below this fraction of the
/// largest count as zero, so contacts redundant up to integration drift count as redundant.
inline constexpr double delassus_rank_threshold = 1e-10;

/// x = A^+ rhs from a complete orthogonal decomposition A P = Q [T 0; 0 0] Z of A. This is
/// CompleteOrthogonalDecomposition::solve, whose Eigen 3.4 version allocates its workspace (a
/// dynamic vector in applyZAdjointOnTheLeftInPlace) when A is rank deficient; here the caller's
/// `work` (at least cols(A) long) is used instead. rhs is overwritten.
template <class Cod, class Rhs, class X, class Work>
void min_norm_solve(const Cod& cod, Rhs& rhs, X& x, Work& work) {
  const int n = static_cast<int>(cod.cols());
  const int rank = static_cast<int>(cod.rank());
  x.setZero(n);
  if (rank == 0) return;
  rhs.applyOnTheLeft(cod.householderQ().setLength(rank).adjoint());
  x.head(rank) = cod.matrixT().topLeftCorner(rank, rank).template triangularView<Eigen::Upper>().solve(rhs.head(rank));
  work.resize(n);
  for (int k = 0; k < rank && rank < n; ++k) {  // Z = I at full rank (zCoeffs unset)
    if (k != rank - 1) std::swap(x[k], x[rank - 1]);
    x.segment(rank - 1, n - rank + 1)
        .applyHouseholderOnTheLeft(cod.matrixQTZ().row(k).tail(n - rank).adjoint(), cod.zCoeffs()(k), work.data());
    if (k != rank - 1) std::swap(x[k], x[rank - 1]);
  }
  work = cod.colsPermutation() * x;
  x = work;
}

/// Minimum-norm solves with a complete orthogonal decomposition of an m x m matrix, m <= MaxN,
/// without heap allocation after construction.
template <int MaxN>
class MinNormSolver {
 public:
  using Matrix = BoundedMatrix<double, Eigen::Dynamic, Eigen::Dynamic, MaxN, MaxN>;
  using Vector = BoundedMatrix<double, Eigen::Dynamic, 1, MaxN, 1>;

  MinNormSolver();
  /// The matrix to factorise, sized m x m; fill it, then call factorize().
  Matrix& matrix(int m);
  void factorize();
  /// b <- A^+ b.
  void solve_in_place(Vector& b) const;
  int rank() const;
  int size() const { return static_cast<int>(A_.rows()); }
  /// Relative rank threshold (default delassus_rank_threshold).
  void set_threshold(double relative);

 private:
  Matrix A_;
  Eigen::CompleteOrthogonalDecomposition<Matrix> cod_;
  mutable Vector tmp_, work_;
};

// Instantiated once in the library for these bounds (contact-problem rows of 1, 2, 4, 8, 16 and
// 32 contacts; hybrid/src/contact_bound_*.cpp); scenes pick the smallest bound that fits
// (delassus_bound). The definitions are in linear_solve.hxx: include it for another bound.
#ifndef SALTUS_CONTACT_NO_EXTERN_TEMPLATES
extern template class MinNormSolver<3>;
extern template class MinNormSolver<6>;
extern template class MinNormSolver<12>;
extern template class MinNormSolver<24>;
extern template class MinNormSolver<48>;
extern template class MinNormSolver<96>;
#endif

inline constexpr int delassus_bound(int rows) {
  return rows <= 3 ? 3 : rows <= 6 ? 6 : rows <= 12 ? 12 : rows <= 24 ? 24 : rows <= 48 ? 48 : rows <= 96 ? 96 : rows;
}

namespace detail {
/// x <- A0^{-1} x for a vector of scalars T, applying a double solver component by component.
template <class Solve, class Vec>
void apply_inverse(const Solve& solve_double, Vec& x) {
  using T = typename Vec::Scalar;
  if constexpr (std::is_same_v<T, double>) {
    solve_double(x);
  } else {
    using U = typename T::value_type;
    using Inner = Eigen::Matrix<U, Vec::RowsAtCompileTime, Vec::ColsAtCompileTime, Vec::Options,
                                Vec::MaxRowsAtCompileTime, Vec::MaxColsAtCompileTime>;
    Inner part(x.rows(), x.cols());
    for (Eigen::Index i = 0; i < x.size(); ++i) part[i] = x[i].value();
    apply_inverse(solve_double, part);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i].value() = part[i];
    for (int k = 0; k < T::directions; ++k) {
      for (Eigen::Index i = 0; i < x.size(); ++i) part[i] = x[i].derivatives()[k];
      apply_inverse(solve_double, part);
      for (Eigen::Index i = 0; i < x.size(); ++i) x[i].derivatives()[k] = part[i];
    }
  }
}
}  // namespace detail

/// Solves A x = b (A with scalars T) given a double solver of value(A) (terminating Neumann
/// series, see the file comment). `solve_double(v)` overwrites a double vector v with A0^{-1} v;
/// `work` is scratch of b's type.
template <class MatA, class VecB, class VecX, class Solve>
void solve_with_value_factorization(const MatA& A, const VecB& b, const Solve& solve_double, VecX& x, VecX& work) {
  using T = typename VecX::Scalar;
  x = b;
  detail::apply_inverse(solve_double, x);
  for (int it = 0; it < ad::order_v<T>; ++it) {
    // work = b - (A - A0) x: the real part of A drops out of the product's perturbation.
    work.noalias() = A * x;
    for (Eigen::Index i = 0; i < work.size(); ++i) {
      T ax0 = T(0);
      for (Eigen::Index j = 0; j < x.size(); ++j) ax0 += ad::value_of(A(i, j)) * x[j];
      work[i] = b[i] - (work[i] - ax0);
    }
    x = work;
    detail::apply_inverse(solve_double, x);
  }
}

/// Minimum-norm solution of A x = b (m x m, m <= MaxN) for scalars T, factorising values only;
/// exact derivatives also where A is rank deficient (see the file comment). Allocation-free.
template <class T, int MaxN>
class MinNormSolve {
 public:
  using MatrixT = BoundedMatrix<T, Eigen::Dynamic, Eigen::Dynamic, MaxN, MaxN>;
  using VectorT = BoundedMatrix<T, Eigen::Dynamic, 1, MaxN, 1>;
  using Vector = typename MinNormSolver<MaxN>::Vector;

  // The Gram matrix squares the singular values of A: a rank threshold of 1e-14 on it matches
  // 1e-7 on A, between round-off (1e-16) and the threshold on A (1e-10) squared.
  MinNormSolve() { gram_.set_threshold(1e-14); }

  template <class MatA, class VecB, class VecX>
  void solve(const MatA& A, const VecB& b, VecX& x) {
    const int m = static_cast<int>(A.rows());
    ad::value_into(A, value_.matrix(m));
    value_.factorize();
    rank_ = value_.rank();
    rows_ = m;
    if constexpr (std::is_same_v<T, double>) {
      x0_ = b;
      value_.solve_in_place(x0_);
      x = x0_;
    } else if (rank_ == m) {
      x_.resize(m);
      work_.resize(m);
      b_ = b;
      solve_with_value_factorization(A, b_, [this](auto& v) { value_.solve_in_place(v); }, x_, work_);
      x = x_;
    } else {
      // Value from the decomposition of A0; derivatives through the Gram system.
      x0_.resize(m);
      for (int i = 0; i < m; ++i) x0_[i] = ad::value_of(b[i]);
      value_.solve_in_place(x0_);
      G_.resize(m, m);
      G_.noalias() = A * A.transpose();
      ad::value_into(G_, gram_.matrix(m));
      gram_.factorize();
      y0_.resize(m);
      for (int i = 0; i < m; ++i) y0_[i] = ad::value_of(b[i]);
      gram_.solve_in_place(y0_);
      y_.resize(m);
      for (int i = 0; i < m; ++i) y_[i] = T(y0_[i]);
      work_.resize(m);
      for (int it = 0; it < ad::order_v<T>; ++it) {
        work_.noalias() = G_ * y_;
        for (int i = 0; i < m; ++i) {
          work_[i] = b[i] - work_[i];
          ad::set_value(work_[i], 0.0);  // zero by consistency; drop its round-off
        }
        detail::apply_inverse([this](auto& v) { gram_.solve_in_place(v); }, work_);
        y_ += work_;
      }
      x_.resize(m);
      x_.noalias() = A.transpose() * y_;
      for (int i = 0; i < m; ++i) ad::set_value(x_[i], x0_[i]);
      x = x_;
    }
  }
  int rank() const { return rank_; }
  int rows() const { return rows_; }

 private:
  MinNormSolver<MaxN> value_, gram_;
  MatrixT G_;
  VectorT x_, y_, b_, work_;
  Vector x0_, y0_;
  int rank_ = 0, rows_ = 0;
};

}  // namespace saltus
