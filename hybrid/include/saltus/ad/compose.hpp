// The chain rule across AD types: a function of a few variables evaluated inside a computation
// that differentiates along many.
//
// Why: the FESD Hessian differentiates each stage's vector field twice along all nz of its local
// variables (forward over forward, Dual<Dual<double, nz>, nz>: 1 + 2 nz + nz^2 numbers per scalar,
// nz = 18 for the plank-box), and the field reads the contact Jacobians J_n(q), J_t(q), which are
// themselves derivatives (one more AD level along the nq coordinates). Those depend on q alone.
// Evaluating them along nq directions and applying the chain rule once costs a small fraction of
// carrying the nz directions through every operation of the scene's kinematics
// (bench/fesd_callbacks.cpp: the measurement, bench/README.md: the table). Used by
// a caller that differentiates along many more directions than n.
//
// compose(x, f) returns f(x) with the derivatives x carries: f is a generic callable
// `[]<class S>(const VecT<S, n>&) -> VecT<S, m>`; it is evaluated at the innermost values of x with
// its own seeds, and its first (and second) derivatives are then contracted with x's. Exact: the
// same derivatives as evaluating f at x's type, up to rounding. Supported x types: double (f itself),
// Dual<double, N> and Dual<Dual<double, N>, N> (the first- and second-order types of the FESD
// callbacks); any other type, or N <= n (nothing to save), evaluates f at x's type directly.
#pragma once

#include <saltus/ad/autodiff.hpp>

#include <Eigen/Core>

namespace saltus::ad {

/// f(x) for any AD type of x: the direct evaluation (compose's fall-back).
template <class T, int n, class F>
auto compose(const Eigen::Matrix<T, n, 1>& x, const F& f) {
  return f(x);
}

/// First order: f's Jacobian along its n inputs (one AD level of n directions), times the N
/// derivatives of x. Result size m = f's.
template <int N, int n, class F>
  requires(N > n)
auto compose(const Eigen::Matrix<Dual<double, N>, n, 1>& x, const F& f) {
  Eigen::Matrix<Dual<double, n>, n, 1> xs;
  Eigen::Matrix<double, n, N> dx;  // row a: x_a's derivatives
  for (int a = 0; a < n; ++a) {
    xs[a] = seed<n>(x[a].value(), a);
    dx.row(a) = x[a].derivatives().transpose();
  }
  const auto y = f(xs);
  constexpr int m = decltype(y)::RowsAtCompileTime;
  Eigen::Matrix<Dual<double, N>, m, 1> out;
  for (int i = 0; i < m; ++i)
    out[i] = Dual<double, N>(y[i].value(), (y[i].derivatives().transpose() * dx).transpose());
  return out;
}

/// Second order, forward over forward. With x_a = x0_a + eps d_a + del e_a + eps del E_a (inner
/// direction eps, outer del), f(x) = f0 + g'(eps d + del e + eps del E) + 1/2 (eps d + del e)' H
/// (eps d + del e) + ..., so the result's inner gradient is D' g, its outer gradient E_o' g and its
/// mixed second derivative (k outer, l inner) sum_a g_a E_a[k][l] + (E_o' H D)(k, l) (H symmetric).
template <int N, int n, class F>
  requires(N > n)
auto compose(const Eigen::Matrix<Dual<Dual<double, N>, N>, n, 1>& x, const F& f) {
  using Inner = Dual<double, N>;
  using Small = Dual<Dual<double, n>, n>;
  Eigen::Matrix<Small, n, 1> xs;
  Eigen::Matrix<double, n, N> d, e;  // row a: x_a's inner and outer first derivatives
  Eigen::Matrix<double, N, N> curvature[n];  // x_a's mixed second derivatives (row k outer)
  bool curved = false;
  for (int a = 0; a < n; ++a) {
    Eigen::Matrix<Dual<double, n>, n, 1> outer;
    for (int b = 0; b < n; ++b) outer[b] = Dual<double, n>(a == b ? 1.0 : 0.0);
    xs[a] = Small(seed<n>(x[a].value().value(), a), outer);
    d.row(a) = x[a].value().derivatives().transpose();
    for (int k = 0; k < N; ++k) {
      e(a, k) = x[a].derivatives()[k].value();
      curvature[a].row(k) = x[a].derivatives()[k].derivatives().transpose();
    }
    curved = curved || !curvature[a].isZero(0.0);
  }
  const auto y = f(xs);
  constexpr int m = decltype(y)::RowsAtCompileTime;
  Eigen::Matrix<Dual<Dual<double, N>, N>, m, 1> out;
  for (int i = 0; i < m; ++i) {
    Eigen::Matrix<double, n, 1> g;
    Eigen::Matrix<double, n, n> h;
    for (int a = 0; a < n; ++a) {
      g[a] = y[i].value().derivatives()[a];
      h.row(a) = y[i].derivatives()[a].derivatives().transpose();
    }
    Eigen::Matrix<double, N, N> second = e.transpose() * (h * d);
    if (curved)
      for (int a = 0; a < n; ++a) second += g[a] * curvature[a];
    const Eigen::Matrix<double, N, 1> outer_gradient = e.transpose() * g;
    Eigen::Matrix<Inner, N, 1> outer;
    for (int k = 0; k < N; ++k) outer[k] = Inner(outer_gradient[k], second.row(k).transpose());
    out[i] = Dual<Inner, N>(Inner(y[i].value().value(), d.transpose() * g), outer);
  }
  return out;
}

}  // namespace saltus::ad
