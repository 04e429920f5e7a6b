// The variational equations' integrator (sensitivity/ only): the library's one adaptive
// Dormand-Prince 5(4) loop (saltus/hybrid/simulation/dopri5_loop.hxx) without events, on
// fixed-size Eigen states. Integrates forwards (t1 > t0) or backwards (t1 < t0); allocation-free.
// Internal: included by definition files (.hxx) only.
#pragma once

#include <saltus/hybrid/simulation/dopri5_loop.hxx>
#include <saltus/sensitivity/detail/ode.hpp>

namespace saltus::detail {

/// x(t1) of x' = rhs(t, x) from x(t0) = x; rhs(t, x, dxdt). @throws NumericalFailure
template <class State, class Rhs>
void integrate_adaptive(Rhs&& rhs, State& x, double t0, double t1, const OdeTolerances& tol) {
  Dopri5Settings settings;
  settings.relative_tolerance = tol.relative;
  settings.absolute_tolerance = tol.absolute;
  settings.initial_step = tol.initial_step;
  settings.max_steps = tol.max_steps;
  settings.what = "variational integration";
  Dopri5Stepper<State> stepper;
  Dopri5Steps steps;
  double t = t0;
  dopri5_integrate(stepper, rhs, t, x, t1, settings, steps,
                   [](double, const State&, const State&, double, const State&, const State&) { return false; });
}

}  // namespace saltus::detail
