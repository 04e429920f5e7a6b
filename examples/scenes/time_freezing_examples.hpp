// The time-freezing paper's guiding example (Example 3) as a simulation case: its input law and
// the closed form of its state at numerical time 3.5 (derivation: bench/fesd_accuracy.cpp, file
// comment). Shared by tests/test_time_freezing.cpp and bench/fesd_accuracy.cpp.
#pragma once

#include <saltus/hybrid/vocabulary/scene.hpp>

#include <cmath>

namespace saltus::scenes {

/// Example 3: g = 9.81 and a_n = g, y0 = (0, 1, 0, 0, 0), tau in [0, 3.5].
struct Example3 {
  static constexpr double gravity = 9.81;
  static constexpr double horizon = 3.5;

  /// u = (7, 0) for t < 1 and (7, 2 g (t - 1)) after (t the physical time, the clock state).
  template <class T>
  VecT<T, 2> input(const T& t, const VecT<T, 2>&) const {
    if (t < 1.0) return VecT<T, 2>(T(7.0), T(0.0));
    return VecT<T, 2>(T(7.0), T(2.0 * gravity * T(t - 1.0)));
  }

  /// (q1, q2, v1, v2, t) at tau = 3.5: t = 2.25, q1 = 3.5 t^2, v1 = 7 t, and after the lift-off at
  /// t = 1.5, v2 = g (t - 1.5)^2, q2 = g (t - 1.5)^3 / 3.
  static Vec<5> final_state() {
    const double t = 2.25;
    return (Vec<5>() << 3.5 * t * t, gravity * std::pow(t - 1.5, 3) / 3.0, 7.0 * t,
            gravity * (t - 1.5) * (t - 1.5), t)
        .finished();
  }
};

}  // namespace saltus::scenes
