// Dense decompositions of the analyses (stability checks, LQR design, numerical twins), compiled
// once in the library (src/dense.cpp) on dynamic-size matrices. Why not Eigen's fixed-size
// decompositions in the scene's templates: each scene's sensitivity translation unit then
// generated its own JacobiSVD, EigenSolver, SelfAdjointEigenSolver, QR and LU code for its own
// sizes: two thirds of that unit's compile time with GCC 12 (hopper: 272 s, 90 s without them;
// docs/build.md). These calls
// run a few hundred times per analysis, never in the simulator's step, so the allocation of a
// dynamic-size decomposition costs nothing measurable. Internal header.
#pragma once

#include <Eigen/Core>

namespace saltus::detail {

using MatrixRef = Eigen::Ref<const Eigen::MatrixXd>;

/// U with W = U' U (Cholesky, upper factor) of a symmetric W (n x n). False if W is not
/// positive definite (U is then unspecified).
bool cholesky_upper(const MatrixRef& W, Eigen::MatrixXd& U);

/// X = A^-1 B for an SPD A (n x n, Cholesky), B (n x m). False if A is not positive definite.
bool spd_solve(const MatrixRef& A, const MatrixRef& B, Eigen::MatrixXd& X);

/// X = A^-1 B for a square A (n x n, LU with partial pivoting), B (n x m). The caller checks
/// that A is invertible (the result is not finite otherwise).
Eigen::MatrixXd lu_solve(const MatrixRef& A, const MatrixRef& B);

/// The largest singular value of P (n x m; 0 for an empty matrix).
double largest_singular_value(const MatrixRef& P);

/// The right singular vector of P's largest singular value (m), unit norm.
Eigen::VectorXd top_right_singular_vector(const MatrixRef& P);

/// The right singular vectors of C (m x n) past its numerical rank (singular values above
/// relative_tolerance * max(1, sigma_max)): an orthonormal basis of its null space (n x (n - rank)).
Eigen::MatrixXd null_space(const MatrixRef& C, double relative_tolerance, int& rank);

/// The eigenvalues of a symmetric A (n x n), ascending; with `vectors`, the orthonormal
/// eigenvectors as columns.
Eigen::VectorXd symmetric_eigenvalues(const MatrixRef& A, Eigen::MatrixXd* vectors = nullptr);

/// The eigenvalues of a general square A (n x n); with `vectors`, the eigenvectors as columns.
Eigen::VectorXcd eigenvalues(const MatrixRef& A, Eigen::MatrixXcd* vectors = nullptr);

/// The R factor (k x k, upper triangular) of the thin Householder QR of B (n x k, k <= n).
Eigen::MatrixXd qr_upper_factor(const MatrixRef& B);

/// x solving D x = b in the least-squares sense by column-pivoted Householder QR (D: m x n).
/// Returns the numerical rank of D (Eigen's default threshold).
int rank_revealing_solve(const MatrixRef& D, const Eigen::Ref<const Eigen::VectorXd>& b, Eigen::VectorXd& x);

/// The minimum-norm least-squares X of B X = R (complete orthogonal decomposition; B: m x n).
Eigen::MatrixXd minimum_norm_solve(const MatrixRef& B, const MatrixRef& R);

/// The point of the convex hull of the rows of P (k x n, k >= 1) nearest to the origin, by
/// Wolfe's algorithm (P. Wolfe, "Finding the nearest point in a polytope", Math. Programming 11,
/// 1976): `point` (n) and its norm returned. Why it serves the cones of the conewise gains: with
/// unit rows, the distance is max over unit d of min_r P_r d when positive (minimax duality), and
/// point / |point| is that d: the direction deepest inside the cone {d : P d >= 0}, every row at
/// least the distance, so the ball of that radius around it lies in the cone. A distance of 0
/// (to round-off) means the cone has no interior (Gordan's alternative). Finite in exact
/// arithmetic; stopped after 50 (k + n) + 100 corrections, where `point` is a hull point (its
/// norm an upper bound on the distance). Exact up to round-off otherwise, for any number of rows.
double nearest_hull_point(const MatrixRef& P, Eigen::VectorXd& point);

}  // namespace saltus::detail
