// The Dormand-Prince 5(4) backend (the simulator's default): the adaptive loop of
// dopri5_loop.hxx (Boost.Odeint's Dormand-Prince stepper, error checker and step adjuster) with
// fixed-size Eigen states (allocation-free); guards are checked at the end of every accepted step
// and at `guard_samples` interior points of its continuous extension, event times are found by
// TOMS 748 on that extension, and the state at the event comes from one more Dormand-Prince step
// from the start of the step to the event time (5th order, rather than the 4th-order extension).
// Definitions in integrator_dopri.hxx (compiled once per scene, see saltus/hybrid/instantiate.hpp).
#pragma once

#include <saltus/hybrid/simulation/integrator.hpp>

namespace saltus {

template <Scene S>
class DormandPrinceIntegrator {
 public:
  static constexpr int nx = 2 * S::nq, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;

  explicit DormandPrinceIntegrator(const IntegratorOptions& options) : options_(options) {}

  /// Integrates sys from (t0, x) towards t_final (> t0, or < t0 backwards); x holds the state at
  /// the end (at an event: the state just before it). Appends pieces to `out` if non-null. With
  /// detect_events = false the guards are not evaluated (reference spreading, the numerical twin).
  /// @throws NumericalFailure on step-size underflow or more than options.max_steps steps.
  SegmentEndOf<S> integrate(ModeSystem<S>& sys, double t0, State& x, double t_final, double simultaneity,
                            DenseOutput<nx>* out, bool detect_events = true);

  /// m: an open contact's gap below -gap_tolerance is a penetration, hence a missed touchdown
  /// (guard_scan.hxx); the simulator sets it to its impact options' gap tolerance.
  void set_gap_tolerance(double gap_tolerance) { gap_tolerance_ = gap_tolerance; }

 private:
  IntegratorOptions options_;
  double gap_tolerance_ = 1e-9;
};

}  // namespace saltus
