// The adaptive Dormand-Prince 5(4) loop, one for the whole library: the simulator's integrator
// (integrator_dopri.hxx: guards, events, dense output) and the variational equations of
// saltus::sensitivity (linearisation.hxx) both step with it.
//
// It uses Boost.Odeint's Dormand-Prince error stepper (the FSAL form do_step(x, f, t, x', f', dt,
// err) and its continuous extension calc_state), its error checker and its step adjuster: the
// step of odeint's controlled_runge_kutta, written out here because that class copies a
// default-constructed stepper whose fixed-size Eigen members are uninitialised (GCC 12 flags it).
// States are fixed-size Eigen vectors (vector_space_algebra), so a step allocates nothing.
// Internal header: it includes Boost.Odeint, so only definition files (.hxx) include it.
#pragma once

#include <algorithm>
// Only the parts of Odeint used here (<boost/numeric/odeint.hpp> parses every stepper: 2.4 s more
// per translation unit).
#include <boost/numeric/odeint/algebra/algebra_dispatcher.hpp>  // before the Eigen dispatcher
#include <boost/numeric/odeint/algebra/vector_space_algebra.hpp>
#include <boost/numeric/odeint/external/eigen/eigen_algebra.hpp>
#include <boost/numeric/odeint/external/eigen/eigen_algebra_dispatcher.hpp>
#include <boost/numeric/odeint/external/eigen/eigen_resize.hpp>
#include <boost/numeric/odeint/stepper/controlled_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>
#include <cmath>
#include <saltus/hybrid/vocabulary/errors.hpp>

namespace saltus::detail {

template <class State>
using Dopri5Stepper = boost::numeric::odeint::runge_kutta_dopri5<State, double, State, double,
                                                                 boost::numeric::odeint::vector_space_algebra>;

struct Dopri5Settings {
  double relative_tolerance = 1e-10;
  double absolute_tolerance = 1e-12;
  double initial_step = 1e-4;  ///< |first step| (s), clipped to the interval
  double max_step = 0.0;       ///< s; 0: unlimited
  long max_steps = 10'000'000;
  /// Names the integration in error messages ("integration of one segment", ...).
  const char* what = "integration";
  /// Appended to the step-size underflow message (a hint at the usual cause).
  const char* underflow_hint = "";
};

struct Dopri5Steps {
  long accepted = 0, rejected = 0;
};

/// Integrates x' = rhs(t, x) (rhs(t, x, xdot)) from (t, x) towards t1 (t1 > t forwards, t1 < t
/// backwards). After every accepted step [ta, tb] it calls
///     on_step(ta, xa, fa, tb, xb, fb)    (f = x' at each end; stepper.calc_state is valid on it)
/// and stops if that returns true, leaving t = tb and x = xb; otherwise it ends with t = t1 and
/// x = x(t1). Returns whether on_step stopped it. @throws NumericalFailure on step-size underflow
/// or more than settings.max_steps accepted steps.
template <class State, class Rhs, class OnStep>
bool dopri5_integrate(Dopri5Stepper<State>& stepper, Rhs&& rhs, double& t, State& x, double t1,
                      const Dopri5Settings& settings, Dopri5Steps& steps, OnStep&& on_step) {
  namespace odeint = boost::numeric::odeint;
  using Checker = odeint::default_error_checker<double, odeint::vector_space_algebra, odeint::default_operations>;
  if (t1 == t) return false;
  const double direction = t1 > t ? 1.0 : -1.0;
  const double max_step = settings.max_step > 0 ? settings.max_step : 0.0;
  const Checker checker(settings.absolute_tolerance, settings.relative_tolerance);
  const odeint::default_step_adjuster<double, double> adjuster(max_step);
  auto system = [&rhs](const State& y, State& dydt, double time) { rhs(time, y, dydt); };
  double dt = direction * std::min(std::abs(settings.initial_step), std::abs(t1 - t));
  State xa = x, fa, xb, fb, error = State::Zero();
  system(xa, fa, t);
  while (direction * (t1 - t) > 0) {
    SALTUS_CHECK_NUMERICS(steps.accepted < settings.max_steps, settings.what, " exceeded ",
                  settings.max_steps, " steps at t = ", t);
    if (max_step > 0 && std::abs(dt) > max_step) dt = direction * max_step;
    const bool last = direction * (t + dt - t1) >= 0;
    if (last) dt = t1 - t;
    const double ta = t;
    stepper.do_step(system, xa, fa, t, xb, fb, dt, error);
    const double err = checker.error(stepper.algebra(), xa, fa, error, dt);
    if (!(err <= 1.0)) {
      dt = adjuster.decrease_step(dt, std::isfinite(err) ? err : 1e10, stepper.error_order());
      SALTUS_CHECK_NUMERICS(std::abs(dt) > 1e-15 * std::max(1.0, std::abs(t)), settings.what,
                    ": step size underflow at t = ", t, settings.underflow_hint);
      ++steps.rejected;
      continue;
    }
    t = last ? t1 : t + dt;
    dt = adjuster.increase_step(dt, err, stepper.stepper_order());
    ++steps.accepted;
    if (on_step(ta, static_cast<const State&>(xa), static_cast<const State&>(fa), t, static_cast<const State&>(xb),
                static_cast<const State&>(fb))) {
      x = xb;
      return true;
    }
    xa = xb;
    fa = fb;
  }
  x = xa;
  return false;
}

}  // namespace saltus::detail
