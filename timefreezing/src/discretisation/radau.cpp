// Radau IIA tableaus for any n_s up to max_radau_stages (construction in radau.hpp).
#include <saltus/timefreezing/discretisation/radau.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace saltus::timefreezing {
namespace {

/// c_1 < .. < c_{n_s - 1}: the zeros of P_{n_s - 1}^{(1,0)}(2c - 1), by Golub-Welsch; c_{n_s} = 1.
Eigen::VectorXd right_radau_nodes(int n_s) {
  Eigen::VectorXd c(n_s);
  c[n_s - 1] = 1.0;
  const int n = n_s - 1;
  if (n == 0) return c;
  const double alpha = 1.0, beta = 0.0;
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) {
    const double s = 2.0 * k + alpha + beta;
    jacobi(k, k) = (beta * beta - alpha * alpha) / (s * (s + 2.0));
    if (k == 0) continue;
    const double off = std::sqrt(4.0 * k * (k + alpha) * (k + beta) * (k + alpha + beta) /
                                 (s * s * (s + 1.0) * (s - 1.0)));
    jacobi(k, k - 1) = jacobi(k - 1, k) = off;
  }
  const Eigen::VectorXd x = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(jacobi, Eigen::EigenvaluesOnly).eigenvalues();
  for (int i = 0; i < n; ++i) c[i] = 0.5 * (x[i] + 1.0);
  std::sort(c.data(), c.data() + n);
  return c;
}

/// Hairer & Wanner II, Table IV.5.5, in closed form (n_s = 1 .. 3).
RadauIIA tabulated_radau_iia(int n_s) {
  RadauIIA t;
  t.stages = n_s;
  t.a.resize(n_s, n_s);
  t.c.resize(n_s);
  if (n_s == 1) {
    t.a << 1.0;
    t.c << 1.0;
  } else if (n_s == 2) {
    t.a << 5.0 / 12.0, -1.0 / 12.0,  //
        3.0 / 4.0, 1.0 / 4.0;
    t.c << 1.0 / 3.0, 1.0;
  } else {
    const double r6 = std::sqrt(6.0);
    t.a << (88.0 - 7.0 * r6) / 360.0, (296.0 - 169.0 * r6) / 1800.0, (-2.0 + 3.0 * r6) / 225.0,  //
        (296.0 + 169.0 * r6) / 1800.0, (88.0 + 7.0 * r6) / 360.0, (-2.0 - 3.0 * r6) / 225.0,      //
        (16.0 - r6) / 36.0, (16.0 + r6) / 36.0, 1.0 / 9.0;
    t.c << (4.0 - r6) / 10.0, (4.0 + r6) / 10.0, 1.0;
  }
  t.b = t.a.row(n_s - 1).transpose();
  return t;
}

}  // namespace

namespace detail {

RadauIIA constructed_radau_iia(int n_s) {
  SALTUS_REQUIRE(n_s >= 1 && n_s <= max_radau_stages, "Radau IIA: the number of stages n_s must be in 1 .. ",
                 max_radau_stages, ", got ", n_s);
  RadauIIA t;
  t.stages = n_s;
  t.c = right_radau_nodes(n_s);
  // C(n_s): A V = W with V(j, k) = c_j^k and W(i, k) = c_i^(k+1) / (k+1), k = 0 .. n_s - 1.
  Eigen::MatrixXd vandermonde(n_s, n_s), integrated(n_s, n_s);
  for (int i = 0; i < n_s; ++i)
    for (int k = 0; k < n_s; ++k) {
      vandermonde(i, k) = std::pow(t.c[i], k);
      integrated(i, k) = std::pow(t.c[i], k + 1) / (k + 1);
    }
  t.a = vandermonde.transpose().fullPivLu().solve(integrated.transpose()).transpose();
  t.b = t.a.row(n_s - 1).transpose();
  return t;
}

}  // namespace detail

RadauIIA radau_iia(int n_s) {
  SALTUS_REQUIRE(n_s >= 1 && n_s <= max_radau_stages, "Radau IIA: the number of stages n_s must be in 1 .. ",
                 max_radau_stages, ", got ", n_s);
  return n_s <= 3 ? tabulated_radau_iia(n_s) : detail::constructed_radau_iia(n_s);
}

}  // namespace saltus::timefreezing
