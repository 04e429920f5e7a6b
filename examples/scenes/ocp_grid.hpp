// The FESD grid the flagship OCPs share (scenes/hopper_holes.hpp, scenes/plank_box_landing.hpp).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>

#include <Eigen/Core>

namespace saltus::scenes {

/// N control intervals over the numerical horizon T~ = T (the physical horizon [s]), N_fe finite
/// elements each, Radau IIA with n_s stages; the terminal clock constraint t(T~) = T, the speed
/// of time s in [1, 5] with rho_s = 0.01 (the time-freezing paper's Section 6 settings), the
/// heuristic step equilibration rho_h = 1, cross-complementarity for the gaps only
/// (velocity_switch_detection = false: the velocities change sign in flight, and the smoothing
/// relaxation needs stage-wise pairs to smooth); the inputs bounded by [lower, upper] (size nu).
inline timefreezing::FesdOptions terminal_clock_grid(double horizon, int control_intervals, int finite_elements,
                                                     int stages, const Eigen::VectorXd& lower,
                                                     const Eigen::VectorXd& upper) {
  timefreezing::FesdOptions o;
  o.stages = stages;
  o.control_intervals = control_intervals;
  o.finite_elements = finite_elements;
  o.horizon = horizon;
  o.clock = timefreezing::ClockConstraint::Terminal;
  o.physical_horizon = horizon;
  o.speed_of_time_max = 5.0;
  o.speed_of_time_weight = 0.01;
  o.step_equilibration_weight = 1.0;
  o.control_lower = lower;
  o.control_upper = upper;
  o.velocity_switch_detection = false;
  return o;
}

}  // namespace saltus::scenes
