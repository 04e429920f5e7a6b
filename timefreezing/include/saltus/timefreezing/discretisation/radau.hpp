// Radau IIA collocation tableaus with n_s = 1, 2, 3 stages (orders 1, 3, 5; stiffly accurate:
// the last stage is the end point of the step, c_{n_s} = 1, so the state at the element boundary
// is the last stage value and b_j = a_{n_s, j}). Coefficients from Hairer & Wanner, "Solving
// Ordinary Differential Equations II", Table IV.5.5 (n_s = 1 is implicit Euler); tests check
// the simplifying conditions B(2 n_s - 1), C(n_s) numerically (test_time_freezing.cpp).
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <Eigen/Core>

#include <cmath>

namespace saltus::timefreezing {

/// Butcher tableau (A: n_s x n_s, b, c: n_s) of Radau IIA.
struct RadauIIA {
  int stages = 0;
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::VectorXd c;
  int order() const { return 2 * stages - 1; }
};

/// Radau IIA with n_s stages. Throws InvalidArgument unless 1 <= n_s <= 3.
inline RadauIIA radau_iia(int n_s) {
  SALTUS_REQUIRE(n_s >= 1 && n_s <= 3, "Radau IIA: the number of stages n_s must be 1, 2 or 3, got ", n_s);
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

}  // namespace saltus::timefreezing
