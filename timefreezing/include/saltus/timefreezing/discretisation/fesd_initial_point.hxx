// FesdMpcc: the bounds of the variables and rows, and the initial points: from the initial state,
// or from a guess of the motion (fesd.hpp).
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/discretisation/fesd.hpp>

#include <algorithm>
#include <limits>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu,
                              Eigen::Ref<Eigen::VectorXd> gl, Eigen::Ref<Eigen::VectorXd> gu) const {
  const double inf = std::numeric_limits<double>::infinity();
  const FesdOptions::Bounds& b = options_.bounds;
  xl.setConstant(-inf);
  xu.setConstant(inf);
  const double gamma = options_.switching.detection ? options_.grid.element_length_freedom : 0.0;
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    xl[speed_index(k)] = 1.0;
    xu[speed_index(k)] = options_.clock.speed_of_time_max;
    for (int i = 0; i < nu; ++i) {
      if (b.control_lower.size() == nu) xl[control_index(k) + i] = b.control_lower[i];
      if (b.control_upper.size() == nu) xu[control_index(k) + i] = b.control_upper[i];
    }
    for (int j = 0; j < options_.grid.finite_elements; ++j) {
      xl[length_index(k, j)] = (1.0 - gamma) * h0_;
      xu[length_index(k, j)] = (1.0 + gamma) * h0_;
      for (int r = 0; r < options_.grid.stages; ++r) {
        const int a = alpha_index(k, j, r);
        for (int m = 0; m < nsw; ++m) {
          xl[a + m] = 0.0;
          xu[a + m] = 1.0;
          xl[a + nsw + m] = 0.0;
          xl[a + 2 * nsw + m] = 0.0;
        }
        for (int i = 0; i < nc; ++i)
          if (!system_.has_friction(i)) {
            xl[a + 3 * i + 2] = 1.0;            // alpha_3 = 1: no tangential switching
            xu[a + 2 * nsw + 3 * i + 2] = 0.0;  // lambda_n,3 = 0
          }
      }
    }
  }
  gl.setZero();
  gu.setZero();
  for (const auto& [row, lower, upper] : inequality_rows_) {
    gl[row] = lower;
    gu[row] = upper;
  }
}

// alpha = 1 where c > 0, 0 where c < 0, 1/2 at 0; lambda_p = max(c, 0), lambda_n = max(-c, 0); a
// frictionless contact's tangential alpha = 1 and lambda_n = 0, as its bounds fix them.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::set_switching_start(Eigen::Ref<Eigen::VectorXd> x, int k, int j, int r, const Vec<nsw>& c) const {
  Vec<nsw> a, lambda_n = (-c).cwiseMax(0.0);
  for (int m = 0; m < nsw; ++m) a[m] = c[m] > 0.0 ? 1.0 : (c[m] < 0.0 ? 0.0 : 0.5);
  for (int i = 0; i < nc; ++i)
    if (!system_.has_friction(i)) {
      a[3 * i + 2] = 1.0;
      lambda_n[3 * i + 2] = 0.0;
    }
  x.template segment<nsw>(alpha_index(k, j, r)) = a;
  x.template segment<nsw>(lambda_p_index(k, j, r)) = c.cwiseMax(0.0);
  x.template segment<nsw>(lambda_n_index(k, j, r)) = lambda_n;
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::initial_point(Eigen::Ref<Eigen::VectorXd> x) const {
  x.setZero();
  Vec<nsw> c0 = system_.template switching_functions<double>(y0_.template head<nq>(), y0_.template segment<nq>(nq));
  for (int m = 0; m < nsw; ++m) c0[m] *= switching_scale(m);
  const FesdOptions::Bounds& b = options_.bounds;
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    x[speed_index(k)] = 1.0;
    for (int i = 0; i < nu; ++i) {
      double u = 0.0;
      if (b.control_lower.size() == nu) u = std::max(u, b.control_lower[i]);
      if (b.control_upper.size() == nu) u = std::min(u, b.control_upper[i]);
      x[control_index(k) + i] = u;
    }
    for (int j = 0; j < options_.grid.finite_elements; ++j) {
      x[length_index(k, j)] = h0_;
      for (int r = 0; r < options_.grid.stages; ++r) {
        x.template segment<ny>(state_index(k, j, r)) = y0_;
        set_switching_start(x, k, j, r, c0);
      }
    }
  }
}

// The guess at t, checked: nx entries, all finite.
template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::guessed_state(const MotionGuess& guess, double t) const -> Vec<nx> {
  const Eigen::VectorXd raw = guess(t);
  SALTUS_REQUIRE(raw.size() == nx, "FESD: initial_point_from_guess: the guess has ", raw.size(), " entries at t = ", t,
                 ", expected nx = 2 nq = ", nx);
  const Vec<nx> g = raw;
  SALTUS_REQUIRE(g.allFinite(), "FESD: initial_point_from_guess: the guess is not finite at t = ", t);
  return g;
}

// Stage point (k, j, r) from the guess at its nominal physical time (initial_point_from_guess).
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::set_stage_from_guess(Eigen::Ref<Eigen::VectorXd> x, int k, int j, int r,
                                            const MotionGuess& guess, double rate) const {
  constexpr double dt = 1e-6;  // central difference of the guessed velocity [s]
  const double tau = ((k * options_.grid.finite_elements + j) + tableau_.c[r]) * h0_;
  const double t = options_.clock.initial_time + rate * tau;
  const Vec<nx> g = guessed_state(guess, t);
  const Vec<nq> accel =
      (guessed_state(guess, t + dt).template tail<nq>() - guessed_state(guess, t - dt).template tail<nq>()) / (2.0 * dt);
  Eigen::Matrix<double, ny, 1> y = Eigen::Matrix<double, ny, 1>::Zero();
  y.template head<nx>() = g;
  y[System::clock_index] = t;
  Eigen::Matrix<double, ny, 1> yd = Eigen::Matrix<double, ny, 1>::Zero();
  yd.template head<nq>() = rate * g.template tail<nq>();
  yd.template segment<nq>(nq) = rate * accel;
  yd[System::clock_index] = rate;
  const Vec<nq> gq = g.template head<nq>(), gv = g.template tail<nq>();
  if constexpr (nc > 0) {
    const Vec<nc> vn = system_.template normal_velocities<double>(gq, gv);
    for (int i = 0; i < nc; ++i) {
      y[System::gap_state_index + i] = system_.scene().template gap<double>(i, gq);
      yd[System::gap_state_index + i] = rate * vn[i];
    }
  }
  x.template segment<ny>(state_index(k, j, r)) = y;
  x.template segment<ny>(derivative_index(k, j, r)) = yd;
  // The guess's integrated gaps are gap(q) (set above), so either reading gives the same c.
  Vec<nsw> c = system_.template switching_functions<double>(gq, gv);
  for (int m = 0; m < nsw; ++m) c[m] *= switching_scale(m);
  set_switching_start(x, k, j, r, c);
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::initial_point_from_guess(Eigen::Ref<Eigen::VectorXd> x_out, const MotionGuess& guess) const {
  SALTUS_REQUIRE(x_out.size() == n_, "FESD: initial_point_from_guess needs ", n_, " entries, got ", x_out.size());
  Eigen::VectorXd x(n_);  // filled here, copied out once every guess value passed its checks
  initial_point(x);
  const FesdOptions::Clock& clock = options_.clock;
  const double rate = clock.constraint == ClockConstraint::None ? 1.0 : clock.physical_horizon / options_.grid.horizon;
  const double speed = std::clamp(rate, 1.0, clock.speed_of_time_max);
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    x[speed_index(k)] = speed;
    for (int j = 0; j < options_.grid.finite_elements; ++j)
      for (int r = 0; r < options_.grid.stages; ++r) set_stage_from_guess(x, k, j, r, guess, rate);
  }
  x_out = x;
}

}  // namespace saltus::timefreezing
