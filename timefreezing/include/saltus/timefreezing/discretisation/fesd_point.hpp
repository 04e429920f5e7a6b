// One point of a discrete FESD solution, as FesdMpcc::points reads it and the recovery takes it.
#pragma once

#include <Eigen/Core>

namespace saltus::timefreezing {

/// One point of the discrete solution: the initial point (element -1) or a stage point.
/// ny = 2 nq + 2 + nc (the time-freezing state), n_switch = 3 nc, nu inputs.
template <int ny, int n_switch, int nu>
struct FesdPoint {
  int interval = 0, element = -1, stage = -1;
  double tau = 0.0;                        ///< numerical time
  Eigen::Matrix<double, ny, 1> y;          ///< (q, v, t, L, g): time_freezing_system.hpp
  Eigen::Matrix<double, n_switch, 1> alpha;
  double ode_weight = 1.0;                 ///< Theta: 1 while the clock runs, 0 when frozen
  Eigen::Matrix<double, nu, 1> u;          ///< the input applied (after the input law)
};

}  // namespace saltus::timefreezing
