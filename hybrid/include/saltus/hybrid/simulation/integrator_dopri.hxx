// Definitions of integrator_dopri.hpp (see there for the method).
#pragma once

#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <limits>
#include <saltus/hybrid/simulation/dopri5_loop.hxx>
#include <saltus/hybrid/simulation/integrator_dopri.hpp>

namespace saltus {

namespace detail {

// Root of every guard that crosses (>= 0 to < 0) in [t_lo, t_hi] of the step [ta, tb], on the
// step's continuous extension; the earliest sets t_first_crossing, and every guard crossing
// within `simultaneity` of it fires.
template <Scene S, class Stepper, class State, class Values>
void locate_guard_crossings(ModeSystem<S>& sys, const Stepper& stepper, const State& xa, const State& fa, double ta,
                            const State& xb, const State& fb, double tb, double t_lo, const Values& g_lo, double t_hi,
                            const Values& g_hi, double simultaneity, double root_tolerance, SegmentEndOf<S>& end) {
  const int n_guards = sys.guards().count;
  Values root{}, gv{};
  State xs;
  double first = std::numeric_limits<double>::infinity();
  const double forward = tb >= ta ? 1.0 : -1.0;
  for (int k = 0; k < n_guards; ++k) {
    root[k] = std::numeric_limits<double>::quiet_NaN();
    if (!(g_lo[k] >= 0.0 && g_hi[k] < 0.0)) continue;
    auto guard_k = [&](double t) {
      stepper.calc_state(t, xs, xa, fa, ta, xb, fb, tb);
      sys.guard_values(t, xs, gv);
      return gv[k];
    };
    if (g_lo[k] == 0.0) {
      root[k] = t_lo;
    } else {
      const double tol = root_tolerance * std::max(1.0, std::abs(t_hi));
      auto stop = [tol](double a, double b) { return std::abs(b - a) <= tol; };
      std::uintmax_t iterations = 200;
      const auto bracket = boost::math::tools::toms748_solve(guard_k, std::min(t_lo, t_hi), std::max(t_lo, t_hi),
                                                             forward > 0 ? g_lo[k] : g_hi[k],
                                                             forward > 0 ? g_hi[k] : g_lo[k], stop, iterations);
      // The side where the guard is still >= 0: the last instant of the mode.
      root[k] = forward > 0 ? bracket.first : bracket.second;
    }
    if (forward * (root[k] - first) < 0 || !std::isfinite(first)) first = root[k];
  }
  end.t_first_crossing = first;
  for (int k = 0; k < n_guards; ++k) end.fired[k] = std::isfinite(root[k]) && std::abs(root[k] - first) <= simultaneity;
}

}  // namespace detail

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
  Values ga{}, gs{};
  if (n_guards > 0) sys.guard_values(t0, x, ga);
  State xs;

  auto on_step = [&](double ta, const State& xa, const State& fa, double tb, const State& xb, const State& fb) {
    if (n_guards > 0) {
      // The earliest sample interval where a guard goes from >= 0 to < 0.
      double t_lo = ta;
      Values g_lo = ga;
      const int samples = std::max(options_.guard_samples, 0);
      bool crossed = false;
      for (int s = 1; s <= samples + 1 && !crossed; ++s) {
        const double ts = s == samples + 1 ? tb : ta + (tb - ta) * double(s) / (samples + 1);
        if (s == samples + 1)
          xs = xb;
        else
          stepper.calc_state(ts, xs, xa, fa, ta, xb, fb, tb);
        sys.guard_values(ts, xs, gs);
        for (int k = 0; k < n_guards; ++k) crossed = crossed || (g_lo[k] >= 0.0 && gs[k] < 0.0);
        if (!crossed) {
          t_lo = ts;
          g_lo = gs;
        } else {
          detail::locate_guard_crossings(sys, stepper, xa, fa, ta, xb, fb, tb, t_lo, g_lo, ts, gs, simultaneity,
                                         options_.root_tolerance, end);
        }
      }
      if (crossed) {
        // Re-step from the start of the step to the event time: 5th-order state at the event.
        Stepper exact;
        State fe;
        const double te = end.t_first_crossing;
        auto system = [&sys](const State& y, State& dydt, double t) { sys.rhs(t, y, dydt); };
        exact.do_step(system, xa, fa, ta, xs, fe, te - ta);
        if (out) {
          State xm;
          exact.calc_state(0.5 * (ta + te), xm, xa, fa, ta, xs, fe, te);
          out->append(quartic_piece<nx>(ta, te, xa, xs, fa, fe, xm));
        }
        end.at_guard = true;
        end.t = te;
        return true;
      }
      ga = gs;
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
