// What an integration backend does for the simulator: integrate the flow of one mode from
// (t0, x0) towards t_final, append its dense output, and stop at the first downward zero
// crossing of a guard, located in time to root_tolerance, reporting every guard that crosses
// within `simultaneity` of it (a simultaneous event). Backends: integrator_dopri.hpp (Boost.Odeint
// Dormand-Prince, the non-stiff default) and integrator_cvode.hpp (SUNDIALS CVODE, BDF or Adams,
// with its own root finding and projection onto the closed contacts).
#pragma once

#include <saltus/hybrid/vocabulary/dense_output.hpp>
#include <saltus/hybrid/simulation/mode_system.hpp>

#include <array>
#include <limits>

namespace saltus {

enum class IntegratorKind { DormandPrince, CvodeBdf, CvodeAdams };

inline const char* to_string(IntegratorKind k) {
  switch (k) {
    case IntegratorKind::DormandPrince: return "dopri5";
    case IntegratorKind::CvodeBdf: return "cvode-bdf";
    case IntegratorKind::CvodeAdams: return "cvode-adams";
  }
  return "?";
}

struct IntegratorOptions {
  IntegratorKind kind = IntegratorKind::DormandPrince;
  double relative_tolerance = 1e-10;
  double absolute_tolerance = 1e-12;
  double initial_step = 1e-4;  ///< s (Dormand-Prince; CVODE estimates its own first step)
  double max_step = 0.0;       ///< s; 0: unlimited
  /// Interior guard checks per step besides its end point (both backends). Between check points
  /// a touchdown that dips below zero and back is found from the gap's exact rate, and one that
  /// starts at round-off below zero from its penetration (simulation/guard_scan.hxx); the other
  /// guards need a sign change at a check point.
  int guard_samples = 2;
  /// Event times are located to root_tolerance * max(1, |t|) on the dense output of the step
  /// (both backends: CVODE's own root, about 100 unit round-offs of t on its interpolant, is
  /// polished with TOMS 748, see integrator_cvode.hpp).
  double root_tolerance = 1e-14;
  long max_steps = 10'000'000;  ///< per segment
  /// CVODE only: project the state onto the closed contacts' constraints (gap = 0, normal
  /// velocity = 0, tangential velocity = 0 when sticking) in the kinetic metric: BDF after every
  /// step (CVodeSetProjFn), Adams only the state at the end of a segment (CVODE projects with BDF
  /// only).
  bool project_constraints = true;
};

/// How an integration ended.
template <int NG>
struct SegmentEnd {
  bool at_guard = false;  ///< false: reached t_final
  double t = 0.0;
  double t_first_crossing = std::numeric_limits<double>::quiet_NaN();
  std::array<bool, NG> fired{};  ///< guards crossing within the simultaneity window
  long steps = 0, rejected_steps = 0;
};

template <Scene S>
using SegmentEndOf = SegmentEnd<2 * S::nc + 1>;

}  // namespace saltus
