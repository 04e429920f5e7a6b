// Radau IIA collocation tableaus with n_s = 1 .. 9 stages (order 2 n_s - 1; stiffly accurate: the
// last stage is the end point of the step, c_{n_s} = 1, so the state at the element boundary is
// the last stage value and b_j = a_{n_s, j}).
//
// Construction (Hairer & Wanner, "Solving Ordinary Differential Equations II", Sec. IV.5): the
// nodes are the right Radau points on [0, 1], c_{n_s} = 1 and c_1 .. c_{n_s - 1} the zeros of the
// Jacobi polynomial P_{n_s - 1}^{(1,0)}(2c - 1). Those zeros are the eigenvalues of the symmetric
// tridiagonal Jacobi matrix of the weight (1 - x) on [-1, 1] (Golub & Welsch 1969): diagonal
// (beta^2 - alpha^2) / ((2k + alpha + beta)(2k + alpha + beta + 2)), k = 0 .. n - 1, off-diagonal
// sqrt(4k (k + alpha)(k + beta)(k + alpha + beta) / ((2k + alpha + beta)^2 (2k + alpha + beta + 1)
// (2k + alpha + beta - 1))), k = 1 .. n - 1, with alpha = 1, beta = 0. The collocation conditions
// C(n_s), sum_j a_ij c_j^(k-1) = c_i^k / k for k = 1 .. n_s, then give A (a Vandermonde system,
// solved with full pivoting: its condition number is 8.6e5 at n_s = 9; B(2 n_s - 1) then holds to
// 1.3e-14). For n_s = 1, 2, 3 the construction reproduces Table IV.5.5 of Hairer & Wanner to
// 1e-16, but those three come from the table's closed forms (n_s = 1 is implicit Euler): the
// time-freezing homotopies are sensitive to perturbations of that size (measured: with the
// constructed n_s = 2 tableau, two tests of test_time_freezing.cpp end elsewhere: a homotopy step
// at sigma = 0.0075 becomes infeasible, a drift of 6.9e-4 appears where there was none). Tests
// check B(2 n_s - 1) and C(n_s) numerically (test_time_freezing.cpp, Radau.*).
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <Eigen/Core>

namespace saltus::timefreezing {

/// Butcher tableau (A: n_s x n_s, b, c: n_s) of Radau IIA.
struct RadauIIA {
  int stages = 0;
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::VectorXd c;
  int order() const { return 2 * stages - 1; }
};

/// The largest n_s that radau_iia builds.
inline constexpr int max_radau_stages = 9;

/// Radau IIA with n_s stages: the closed forms for n_s <= 3, the construction above beyond.
/// Throws InvalidArgument unless 1 <= n_s <= max_radau_stages.
RadauIIA radau_iia(int n_s);

namespace detail {
/// The construction for any n_s in 1 .. max_radau_stages (tests compare it with the closed forms).
RadauIIA constructed_radau_iia(int n_s);
}  // namespace detail

}  // namespace saltus::timefreezing
