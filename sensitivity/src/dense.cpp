// The analyses' dense decompositions, compiled once (detail/dense.hpp says why).
#include <saltus/sensitivity/detail/dense.hpp>

#include <Eigen/Dense>
#include <algorithm>

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

}  // namespace saltus::detail
