// Tolerances of the variational equations' integrator (detail/ode.hxx), a public option of the
// linearisation (LinearisedSystemOptions::variational).
#pragma once

namespace saltus::detail {

struct OdeTolerances {
  double relative = 1e-12;
  double absolute = 1e-13;
  double initial_step = 1e-4;
  long max_steps = 10'000'000;
};

}  // namespace saltus::detail
