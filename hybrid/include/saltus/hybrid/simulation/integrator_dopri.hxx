// Definitions of integrator_dopri.hpp (see there for the method).
#pragma once

#include <cmath>
#include <limits>
#include <saltus/hybrid/simulation/dopri5_loop.hxx>
#include <saltus/hybrid/simulation/guard_scan.hxx>
#include <saltus/hybrid/simulation/integrator_dopri.hpp>

namespace saltus {


template <Scene S>
SegmentEndOf<S> DormandPrinceIntegrator<S>::integrate(ModeSystem<S>& sys, double t0, State& x, double t_final,
                                                      double simultaneity, DenseOutput<nx>* out, bool detect_events) {
  using Stepper = detail::Dopri5Stepper<State>;
  using Values = typename ModeSystem<S>::GuardValues;
  SegmentEndOf<S> end;
  detail::Dopri5Settings settings;
  settings.relative_tolerance = options_.relative_tolerance;
  settings.absolute_tolerance = options_.absolute_tolerance;
  settings.initial_step = options_.initial_step;
  settings.max_step = options_.max_step;
  settings.max_steps = options_.max_steps;
  settings.what = "integration of one segment";
  settings.underflow_hint = " (stiff mode, or a discontinuous input?)";
  detail::Dopri5Steps steps;
  Stepper stepper;
  auto rhs = [&sys](double t, const State& y, State& dydt) { sys.rhs(t, y, dydt); };
  const int n_guards = detect_events ? sys.guards().count : 0;
  Values ga{}, ra{};
  if (n_guards > 0) sys.guard_values(t0, x, ga, &ra);
  const auto scan = detail::GuardScanSettings::of(options_, gap_tolerance_, simultaneity);
  State xs;

  auto on_step = [&](double ta, const State& xa, const State& fa, double tb, const State& xb, const State& fb) {
    if (n_guards > 0) {
      auto state_at = [&](double t, State& y) {
        if (t == tb)
          y = xb;
        else
          stepper.calc_state(t, y, xa, fa, ta, xb, fb, tb);
      };
      if (detail::scan_step_for_events(sys, state_at, ta, tb, ga, ra, scan, end)) {
        // Re-step from the start of the step to the event time: 5th-order state at the event.
        const double te = end.t_first_crossing;
        if (te > ta) {
          Stepper exact;
          State fe;
          auto system = [&sys](const State& y, State& dydt, double t) { sys.rhs(t, y, dydt); };
          exact.do_step(system, xa, fa, ta, xs, fe, te - ta);
          if (out) {
            State xm;
            exact.calc_state(0.5 * (ta + te), xm, xa, fa, ta, xs, fe, te);
            out->append(quartic_piece<nx>(ta, te, xa, xs, fa, fe, xm));
          }
        } else {
          xs = xa;  // the event is at the step's start (a contact that never really left)
        }
        end.at_guard = true;
        end.t = te;
        return true;
      }
    }
    if (out) {
      State xm;
      stepper.calc_state(0.5 * (ta + tb), xm, xa, fa, ta, xb, fb, tb);
      out->append(quartic_piece<nx>(ta, tb, xa, xb, fa, fb, xm));
    }
    return false;
  };

  double t = t0;
  const bool at_event = detail::dopri5_integrate(stepper, rhs, t, x, t_final, settings, steps, on_step);
  end.steps = steps.accepted;
  end.rejected_steps = steps.rejected;
  if (at_event) {
    x = xs;  // the state at the event, not the end of the step
  } else {
    end.t = t;
  }
  return end;
}

}  // namespace saltus
