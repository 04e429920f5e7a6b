// What the refinement starts from: a mode schedule with its event times, the initial state and
// horizon of the OCP, and a guess of the motion (state per phase, input) to initialise the NLP.
#pragma once

#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <saltus/timefreezing/refinement/mode_schedule.hpp>

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

namespace saltus::timefreezing {

/// The data of an OCP that the time-freezing solver reads from FesdOptions and the initial
/// state (the OCP struct itself holds the costs and constraints): x0 = (q0, v0) at t0, the
/// physical final time, the bounds of the input (decision) u. Sizes: x0 2 nq; bounds nu or empty
/// (unbounded).
template <Scene S>
struct OcpHorizon {
  VecT<double, 2 * S::nq> x0 = VecT<double, 2 * S::nq>::Zero();
  double initial_time = 0.0;                                       ///< t0 [s]
  double final_time = std::numeric_limits<double>::quiet_NaN();    ///< T [s], > t0
  Eigen::VectorXd control_lower, control_upper;

  /// Throws InvalidArgument naming the field: x0 not finite, times not finite or T <= t0, bounds of
  /// the wrong size or lower > upper.
  void validate() const {
    require_finite(x0, "OCP horizon: the initial state x0");
    SALTUS_REQUIRE(std::isfinite(initial_time) && std::isfinite(final_time) && final_time > initial_time,
                   "OCP horizon: needs finite t0 < T, got t0 = ", initial_time, ", T = ", final_time);
    for (const Eigen::VectorXd* b : {&control_lower, &control_upper})
      SALTUS_REQUIRE(b->size() == 0 || b->size() == S::nu, "OCP horizon: input bounds need nu = ", S::nu,
                     " entries, got ", b->size());
    if (control_lower.size() == S::nu && control_upper.size() == S::nu)
      for (int k = 0; k < S::nu; ++k)
        SALTUS_REQUIRE(!(control_lower[k] > control_upper[k]), "OCP horizon: input ", k, " has lower bound ",
                       control_lower[k], " > upper bound ", control_upper[k]);
  }
};

/// A schedule with its event times and a guess of the motion in it. state(k, t): x on phase k at t
/// (at an event time, the side of phase k: x- for the phase that ends there, x+ for the one that
/// starts); input(t): u at t.
template <Scene S>
struct ScheduleGuess {
  ModeSchedule<S::nc> schedule;
  std::vector<double> event_times;  ///< one per event, non-decreasing, within [t0, T]
  std::function<VecT<double, 2 * S::nq>(int phase, double t)> state;
  std::function<VecT<double, S::nu>(double t)> input;
};

}  // namespace saltus::timefreezing
