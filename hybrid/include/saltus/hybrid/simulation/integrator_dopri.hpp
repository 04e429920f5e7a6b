// The Dormand-Prince 5(4) backend: Boost.Odeint's Dormand-Prince error stepper, its error checker
// and step adjuster (the step of odeint's controlled_runge_kutta, written out here because that
// class copies a default-constructed stepper whose fixed-size Eigen members are uninitialised,
// which GCC 12 flags), with fixed-size Eigen states (allocation-free), guards checked at the end of every accepted step and at interior
// points of its continuous extension, event times found by TOMS 748 on that extension, and the
// state at the event obtained by one more Dormand-Prince step from the start of the step to the
// event time (5th order, rather than the 4th-order extension).
#pragma once

#include <saltus/hybrid/simulation/integrator.hpp>

#include <boost/math/tools/roots.hpp>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>

#include <cmath>

namespace saltus {

template <Scene S>
class DormandPrinceIntegrator {
 public:
  static constexpr int nx = 2 * S::nq, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;
  using Stepper = boost::numeric::odeint::runge_kutta_dopri5<State, double, State, double,
                                                            boost::numeric::odeint::vector_space_algebra>;
  using ErrorChecker = boost::numeric::odeint::default_error_checker<double, boost::numeric::odeint::vector_space_algebra,
                                                                      boost::numeric::odeint::default_operations>;
  using StepAdjuster = boost::numeric::odeint::default_step_adjuster<double, double>;

  explicit DormandPrinceIntegrator(const IntegratorOptions& options) : options_(options) {}

  /// Integrates sys from (t0, x0) towards t_final (> t0, or < t0 backwards); x holds the state at
  /// the end (at the event: the state just before it). Appends pieces to `out` if non-null.
  SegmentEndOf<S> integrate(ModeSystem<S>& sys, double t0, State& x, double t_final, double simultaneity,
                            DenseOutput<nx>* out, bool detect_events = true) {
    namespace odeint = boost::numeric::odeint;
    SegmentEndOf<S> end;
    const double direction = t_final >= t0 ? 1.0 : -1.0;
    const double max_step = options_.max_step > 0 ? options_.max_step : 0.0;
    const ErrorChecker checker(options_.absolute_tolerance, options_.relative_tolerance);
    const StepAdjuster adjuster(max_step);
    State error = State::Zero();
    auto system = [&sys](const State& y, State& dydt, double t) { sys.rhs(t, y, dydt); };
    const int n_guards = detect_events ? sys.guards().count : 0;

    double t = t0;
    double dt = direction * std::min(std::abs(options_.initial_step), std::abs(t_final - t0));
    State xa = x, fa, xb, fb, xs;
    system(xa, fa, t);
    std::array<double, ng> ga{}, gs{};
    if (n_guards > 0) sys.guard_values(t, xa, ga);

    while (direction * (t_final - t) > 0) {
      SALTUS_DEMAND(end.steps < options_.max_steps, NumericalFailure, "integration of one segment exceeded ",
                    options_.max_steps, " steps at t = ", t);
      if (max_step > 0 && std::abs(dt) > max_step) dt = direction * max_step;
      const bool reaches_final = direction * (t + dt - t_final) >= 0;
      if (reaches_final) dt = t_final - t;
      const double ta = t;
      stepper_.do_step(system, xa, fa, t, xb, fb, dt, error);
      const double err = checker.error(stepper_.algebra(), xa, fa, error, dt);
      if (!(err <= 1.0)) {
        dt = adjuster.decrease_step(dt, std::isfinite(err) ? err : 1e10, stepper_.error_order());
        SALTUS_DEMAND(std::abs(dt) > 1e-15 * std::max(1.0, std::abs(t)), NumericalFailure,
                      "step size underflow at t = ", t, " (stiff mode, or a discontinuous input?)");
        ++end.rejected_steps;
        continue;
      }
      t = reaches_final ? t_final : t + dt;
      dt = adjuster.increase_step(dt, err, stepper_.stepper_order());
      ++end.steps;
      const double tb = t;
      if (n_guards > 0) {
        // Find the earliest sample interval where a guard goes from >= 0 to < 0.
        double t_lo = ta;
        std::array<double, ng> g_lo = ga;
        int samples = std::max(options_.guard_samples, 0);
        bool crossed = false;
        for (int s = 1; s <= samples + 1 && !crossed; ++s) {
          const double ts = s == samples + 1 ? tb : ta + (tb - ta) * double(s) / (samples + 1);
          if (s == samples + 1)
            xs = xb;
          else
            stepper_.calc_state(ts, xs, xa, fa, ta, xb, fb, tb);
          sys.guard_values(ts, xs, gs);
          for (int k = 0; k < n_guards; ++k) crossed = crossed || (g_lo[k] >= 0.0 && gs[k] < 0.0);
          if (!crossed) {
            t_lo = ts;
            g_lo = gs;
          } else {
            locate(sys, xa, fa, ta, xb, fb, tb, t_lo, g_lo, ts, gs, simultaneity, end);
          }
        }
        if (crossed) {
          // Re-step from the start of the step to the event time: 5th-order state at the event.
          Stepper exact;
          State fe;
          const double te = end.t_first_crossing;
          exact.do_step(system, xa, fa, ta, xs, fe, te - ta);
          if (out) {
            State xm;
            exact.calc_state(0.5 * (ta + te), xm, xa, fa, ta, xs, fe, te);
            out->append(quartic_piece<nx>(ta, te, xa, xs, fa, fe, xm));
          }
          x = xs;
          end.at_guard = true;
          end.t = te;
          return end;
        }
        ga = gs;
      }
      if (out) {
        State xm;
        stepper_.calc_state(0.5 * (ta + tb), xm, xa, fa, ta, xb, fb, tb);
        out->append(quartic_piece<nx>(ta, tb, xa, xb, fa, fb, xm));
      }
      xa = xb;
      fa = fb;
    }
    x = xa;
    end.t = t;
    return end;
  }

 private:
  // Root of every guard that crosses in [t_lo, t_hi] on the continuous extension; the earliest
  // sets t_first_crossing, and every guard crossing within `simultaneity` of it fires.
  void locate(ModeSystem<S>& sys, const State& xa, const State& fa, double ta, const State& xb,
              const State& fb, double tb, double t_lo, const std::array<double, ng>& g_lo, double t_hi,
              const std::array<double, ng>& g_hi, double simultaneity, SegmentEndOf<S>& end) {
    const int n_guards = sys.guards().count;
    std::array<double, ng> root{};
    State xs;
    std::array<double, ng> gv{};
    double first = std::numeric_limits<double>::infinity();
    const double forward = tb >= ta ? 1.0 : -1.0;
    for (int k = 0; k < n_guards; ++k) {
      root[k] = std::numeric_limits<double>::quiet_NaN();
      if (!(g_lo[k] >= 0.0 && g_hi[k] < 0.0)) continue;
      auto guard_k = [&](double t) {
        stepper_.calc_state(t, xs, xa, fa, ta, xb, fb, tb);
        sys.guard_values(t, xs, gv);
        return gv[k];
      };
      if (g_lo[k] == 0.0) {
        root[k] = t_lo;
      } else {
        const double tol = options_.root_tolerance * std::max(1.0, std::abs(t_hi));
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
    for (int k = 0; k < n_guards; ++k)
      end.fired[k] = std::isfinite(root[k]) && std::abs(root[k] - first) <= simultaneity;
  }

  IntegratorOptions options_;
  Stepper stepper_;
};

}  // namespace saltus
