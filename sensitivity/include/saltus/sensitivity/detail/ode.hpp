// A small adaptive Dormand-Prince 5(4) loop on fixed-size Eigen states for the variational
// equations (sensitivity/ only). It uses Boost.Odeint's stepper, error checker and step adjuster
// the way hybrid/integrator_dopri.hpp does (not odeint's controlled_runge_kutta, which copies a
// default-constructed stepper whose fixed-size Eigen members are uninitialised). Integrates
// forwards (t1 > t0) or backwards (t1 < t0); allocation-free.
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>

#include <algorithm>
#include <cmath>

namespace saltus::detail {

struct OdeTolerances {
  double relative = 1e-12;
  double absolute = 1e-13;
  double initial_step = 1e-4;
  long max_steps = 10'000'000;
};

/// x(t1) of x' = rhs(t, x) from x(t0) = x; rhs(t, x, dxdt).
template <class State, class Rhs>
void integrate_adaptive(Rhs&& rhs, State& x, double t0, double t1, const OdeTolerances& tol) {
  namespace odeint = boost::numeric::odeint;
  using Stepper = odeint::runge_kutta_dopri5<State, double, State, double, odeint::vector_space_algebra>;
  using Checker = odeint::default_error_checker<double, odeint::vector_space_algebra, odeint::default_operations>;
  if (t1 == t0) return;
  Stepper stepper;
  const Checker checker(tol.absolute, tol.relative);
  const odeint::default_step_adjuster<double, double> adjuster(0.0);
  auto system = [&rhs](const State& y, State& dydt, double t) { rhs(t, y, dydt); };
  const double direction = t1 > t0 ? 1.0 : -1.0;
  double t = t0;
  double dt = direction * std::min(std::abs(tol.initial_step), std::abs(t1 - t0));
  State xa = x, fa, xb, fb, err;
  system(xa, fa, t);
  long steps = 0;
  while (direction * (t1 - t) > 0) {
    SALTUS_DEMAND(++steps <= tol.max_steps, NumericalFailure, "variational integration exceeded ", tol.max_steps,
                  " steps at t = ", t);
    const bool last = direction * (t + dt - t1) >= 0;
    if (last) dt = t1 - t;
    stepper.do_step(system, xa, fa, t, xb, fb, dt, err);
    const double e = checker.error(stepper.algebra(), xa, fa, err, dt);
    if (!(e <= 1.0)) {
      dt = adjuster.decrease_step(dt, std::isfinite(e) ? e : 1e10, stepper.error_order());
      SALTUS_DEMAND(std::abs(dt) > 1e-15 * std::max(1.0, std::abs(t)), NumericalFailure,
                    "variational integration: step size underflow at t = ", t);
      continue;
    }
    t = last ? t1 : t + dt;
    dt = adjuster.increase_step(dt, e, stepper.stepper_order());
    xa = xb;
    fa = fb;
  }
  x = xa;
}

}  // namespace saltus::detail
