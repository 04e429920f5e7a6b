// Shared by the time-freezing tests: a point of an MPCC inside its variable bounds, away from its
// initial guess (where derivative checks would see the special values of the start).
#pragma once

#include <saltus/timefreezing/mpcc/mpcc.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace saltus::testing {

/// Bounded variables: uniform in their bounds; others: the initial point plus up to 0.2, kept
/// 0.05 above a lower bound. Seeded by std::srand(seed) (Eigen's Random).
inline Eigen::VectorXd interior_point(const timefreezing::Mpcc& problem, unsigned seed) {
  const int n = problem.variable_count(), m = problem.constraint_count();
  Eigen::VectorXd x(n), xl(n), xu(n), gl(m), gu(m);
  problem.initial_point(x);
  problem.bounds(xl, xu, gl, gu);
  std::srand(seed);
  const Eigen::VectorXd r = Eigen::VectorXd::Random(n);
  for (int i = 0; i < n; ++i) {
    x[i] += 0.2 * r[i];
    if (std::isfinite(xl[i]) && std::isfinite(xu[i])) x[i] = xl[i] + 0.5 * (1.0 + r[i]) * (xu[i] - xl[i]);
    else if (std::isfinite(xl[i])) x[i] = std::max(x[i], xl[i] + 0.05);
  }
  return x;
}

}  // namespace saltus::testing
