// The FESD grid the flagship OCPs share (scenes/hopper_holes.hpp, scenes/plank_box_landing.hpp).
#pragma once

#include <saltus/timefreezing/discretisation/fesd_options.hpp>

#include <Eigen/Core>

namespace saltus::scenes {

/// N control intervals over the numerical horizon T~ = T (the physical horizon [s]), N_fe finite
/// elements each, Radau IIA with n_s stages; the terminal clock constraint t(T~) = T, the speed
/// of time s in [1, 5] with rho_s = 0.01 (the time-freezing paper's Section 6 settings), the
/// heuristic step equilibration rho_h = 1, cross-complementarity for the gaps only
/// (switching.velocity_detection = false: the velocities change sign in flight, and the smoothing
/// relaxation needs stage-wise pairs to smooth); the inputs bounded by [lower, upper] (size nu).
inline timefreezing::FesdOptions terminal_clock_grid(double horizon, int control_intervals, int finite_elements,
                                                     int stages, const Eigen::VectorXd& lower,
                                                     const Eigen::VectorXd& upper) {
  timefreezing::FesdOptions o;
  o.grid.stages = stages;
  o.grid.control_intervals = control_intervals;
  o.grid.finite_elements = finite_elements;
  o.grid.horizon = horizon;
  o.clock.constraint = timefreezing::ClockConstraint::Terminal;
  o.clock.physical_horizon = horizon;
  o.clock.speed_of_time_max = 5.0;
  o.regularisation.speed_of_time = 0.01;
  o.regularisation.step_equilibration = 1.0;
  o.bounds.control_lower = lower;
  o.bounds.control_upper = upper;
  o.switching.velocity_detection = false;
  return o;
}

}  // namespace saltus::scenes
