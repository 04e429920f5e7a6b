// The analyses' dense decompositions, compiled once (detail/dense.hpp says why).
#include <saltus/sensitivity/detail/dense.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <numeric>
#include <vector>

namespace saltus::detail {

bool cholesky_upper(const MatrixRef& W, Eigen::MatrixXd& U) {
  const Eigen::LLT<Eigen::MatrixXd> llt(W);
  if (llt.info() != Eigen::Success) return false;
  U = llt.matrixU();
  return true;
}

bool spd_solve(const MatrixRef& A, const MatrixRef& B, Eigen::MatrixXd& X) {
  const Eigen::LLT<Eigen::MatrixXd> llt(A);
  if (llt.info() != Eigen::Success) return false;
  X = llt.solve(B);
  return true;
}

Eigen::MatrixXd lu_solve(const MatrixRef& A, const MatrixRef& B) { return Eigen::PartialPivLU<Eigen::MatrixXd>(A).solve(B); }

double largest_singular_value(const MatrixRef& P) {
  if (P.size() == 0) return 0.0;
  return Eigen::JacobiSVD<Eigen::MatrixXd>(P).singularValues()(0);
}

Eigen::VectorXd top_right_singular_vector(const MatrixRef& P) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(P, Eigen::ComputeFullV);
  return svd.matrixV().col(0);
}

Eigen::MatrixXd null_space(const MatrixRef& C, double relative_tolerance, int& rank) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(C, Eigen::ComputeFullV);
  const auto& sigma = svd.singularValues();
  const double tol = relative_tolerance * std::max(1.0, sigma.size() ? sigma[0] : 0.0);
  rank = 0;
  while (rank < sigma.size() && sigma[rank] > tol) ++rank;
  return svd.matrixV().rightCols(C.cols() - rank);
}

Eigen::VectorXd symmetric_eigenvalues(const MatrixRef& A, Eigen::MatrixXd* vectors) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A, vectors ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (vectors) *vectors = es.eigenvectors();
  return es.eigenvalues();
}

Eigen::VectorXcd eigenvalues(const MatrixRef& A, Eigen::MatrixXcd* vectors) {
  const Eigen::EigenSolver<Eigen::MatrixXd> es(A, vectors != nullptr);
  if (vectors) *vectors = es.eigenvectors();
  return es.eigenvalues();
}

Eigen::MatrixXd qr_upper_factor(const MatrixRef& B) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(B);
  return qr.matrixQR().topRows(B.cols()).triangularView<Eigen::Upper>();
}

int rank_revealing_solve(const MatrixRef& D, const Eigen::Ref<const Eigen::VectorXd>& b, Eigen::VectorXd& x) {
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(D);
  x = qr.solve(b);
  return static_cast<int>(qr.rank());
}

Eigen::MatrixXd minimum_norm_solve(const MatrixRef& B, const MatrixRef& R) {
  return Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(B).solve(R);
}

double nearest_hull_point(const MatrixRef& P, Eigen::VectorXd& point) {
  const int k = static_cast<int>(P.rows()), n = static_cast<int>(P.cols());
  point = Eigen::VectorXd::Zero(n);
  if (k == 0) return 0.0;
  double scale2 = 0.0;
  int first = 0;
  for (int i = 0; i < k; ++i) {
    scale2 = std::max(scale2, P.row(i).squaredNorm());
    if (P.row(i).squaredNorm() < P.row(first).squaredNorm()) first = i;
  }
  if (!(scale2 > 0)) return 0.0;
  // The corral S (affinely independent rows) and the convex weights of `point` on it.
  std::vector<int> S{first};
  std::vector<double> weight{1.0};
  point = P.row(first).transpose();
  constexpr double tiny = 1e-15;
  for (int major = 0; major < 50 * (k + n) + 100; ++major) {
    if (point.squaredNorm() <= tiny * tiny * scale2) break;  // the origin is (numerically) in the hull
    // The row most opposed to `point`: if no row is below the supporting plane through it, it is optimal.
    const Eigen::VectorXd along = P * point;
    int j = 0;
    along.minCoeff(&j);
    if (point.squaredNorm() - along[j] <= tiny * scale2) break;
    if (std::find(S.begin(), S.end(), j) != S.end()) break;  // round-off: no progress is possible
    S.push_back(j);
    weight.push_back(0.0);
    for (int minor = 0; minor <= n + 1; ++minor) {
      // The point of the affine hull of S nearest to the origin: p0 + D mu, D = [p_i - p0].
      const int s = static_cast<int>(S.size());
      const Eigen::VectorXd p0 = P.row(S[0]).transpose();
      Eigen::VectorXd alpha(s);
      if (s == 1) {
        alpha[0] = 1.0;
      } else {
        Eigen::MatrixXd D(n, s - 1);
        for (int i = 1; i < s; ++i) D.col(i - 1) = P.row(S[i]).transpose() - p0;
        const Eigen::VectorXd mu = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(D).solve(Eigen::VectorXd(-p0));
        alpha[0] = 1.0 - mu.sum();
        alpha.tail(s - 1) = mu;
      }
      if (alpha.minCoeff() > tiny) {  // inside the simplex of S: the new point
        for (int i = 0; i < s; ++i) weight[i] = alpha[i];
        break;
      }
      // Otherwise move from the current weights towards alpha until a weight reaches zero, and
      // drop the rows whose weight did (the minor cycle of Wolfe's algorithm).
      double theta = 1.0;
      for (int i = 0; i < s; ++i)
        if (alpha[i] <= tiny && weight[i] - alpha[i] > 0) theta = std::min(theta, weight[i] / (weight[i] - alpha[i]));
      std::vector<int> kept;
      std::vector<double> kept_weight;
      for (int i = 0; i < s; ++i) {
        const double w = weight[i] + theta * (alpha[i] - weight[i]);
        if (w > tiny) {
          kept.push_back(S[i]);
          kept_weight.push_back(w);
        }
      }
      if (kept.empty()) {  // round-off: keep the newest row alone
        kept = {S.back()};
        kept_weight = {1.0};
      }
      S = std::move(kept);
      weight = std::move(kept_weight);
      const double total = std::accumulate(weight.begin(), weight.end(), 0.0);
      for (double& w : weight) w /= total;
      if (S.size() == 1) break;
    }
    point.setZero();
    for (std::size_t i = 0; i < S.size(); ++i) point += weight[i] * P.row(S[i]).transpose();
  }
  return point.norm();
}

}  // namespace saltus::detail
