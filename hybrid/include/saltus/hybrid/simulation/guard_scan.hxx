// The event search over one accepted step, shared by both backends (integrator_dopri.hxx,
// integrator_cvode.hxx). Internal header: included by definition files only.
//
// A guard gamma_k is checked at the step's end and at `samples` interior points of the step's
// continuous extension x(t); between consecutive check points [t_lo, t_s] a guard fires when
//  1. it crosses: gamma(t_lo) >= 0 > gamma(t_s) (every guard kind); the event time is the root,
//     located by TOMS 748 on the extension, on its >= 0 side (the last instant of the mode). A
//     touchdown that ends within gap_tolerance below zero while rising is not an approach (the
//     integration error of a contact that leaves the surface) and does not fire;
//  2. a touchdown dips below zero and back between the check points (gamma >= 0 at both ends, the
//     gap's exact rate zeta_n = w_n^T v negative at t_lo and positive at t_s): the gap's minimum
//     t_m is the root of zeta_n, and if gamma(t_m) < -dip_depth (1e-3 gap_tolerance) the crossing
//     is located in [t_lo, t_m]. A grazing motion (a minimum at zero up to round-off, or above)
//     fires nothing, so a trajectory that grazes or misses the table stays exactly what it was;
//  3. a touchdown that starts slightly below zero (a contact released at round-off below the
//     surface: gap -1e-16 after a lift-off) ends below -gap_tolerance and lower than it started:
//     a flight too short for case 1 to see (it never was >= 0 at a check point). If the gap has
//     a maximum t_M inside (zeta_n > 0 at t_lo, < 0 at t_s) at gamma(t_M) >= 0, the crossing is
//     located in [t_M, t_s]; if that maximum is below zero the contact never really left and it
//     touches at t_M with zero normal velocity; without a maximum (approaching from the start)
//     it touches at t_lo.
// Cases 2 and 3 make the step's post-condition an invariant: no open contact ends an accepted
// step below -gap_tolerance unless it started the step lower still (the drift of a contact
// released below the surface, which rises).
#pragma once

#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <saltus/hybrid/simulation/integrator.hpp>
#include <saltus/hybrid/simulation/mode_system.hpp>

namespace saltus::detail {

struct GuardScanSettings {
  int samples = 2;               ///< interior check points per step
  double gap_tolerance = 1e-9;   ///< m: a gap below -gap_tolerance is a penetration
  double simultaneity = 1e-9;    ///< s: roots this close to the first one fire together
  double root_tolerance = 1e-14; ///< relative tolerance of a located event time
  /// m: a dip between check points fires only below -dip_depth (1e-3 gap_tolerance), so that a
  /// motion that grazes the surface (a minimum at zero up to round-off) is left unchanged.
  double dip_depth = 1e-12;

  /// The settings of a backend's options and the simulator's tolerances.
  static GuardScanSettings of(const IntegratorOptions& options, double gap_tolerance, double simultaneity) {
    return {options.guard_samples, gap_tolerance, simultaneity, options.root_tolerance, 1e-3 * gap_tolerance};
  }
};

/// Scans the accepted step [ta, tb] (ta < tb) for the first event (file comment). state_at(t, x)
/// writes the continuous extension at t in [ta, tb]; g_a and r_a hold the guard values and
/// touchdown rates at ta and are advanced to tb when nothing fires. Returns true at an event,
/// with end.t_first_crossing and end.fired set.
template <Scene S, class StateAt>
bool scan_step_for_events(ModeSystem<S>& sys, StateAt&& state_at, double ta, double tb,
                          typename ModeSystem<S>::GuardValues& g_a, typename ModeSystem<S>::GuardValues& r_a,
                          const GuardScanSettings& settings, SegmentEndOf<S>& end) {
  using Values = typename ModeSystem<S>::GuardValues;
  using State = typename ModeSystem<S>::State;
  const int n_guards = sys.guards().count;
  if (n_guards == 0) return false;
  SALTUS_INVARIANT(tb > ta, "the guard scan runs forwards in time");
  State xs;
  Values gv{}, rv{};
  auto guard = [&](int k, double t) {
    state_at(t, xs);
    sys.guard_values(t, xs, gv);
    return gv[k];
  };
  auto rate = [&](int k, double t) {
    state_at(t, xs);
    sys.guard_values(t, xs, gv, &rv);
    return rv[k];
  };
  const double tol = settings.root_tolerance * std::max(1.0, std::abs(tb));
  auto stop = [tol](double a, double b) { return std::abs(b - a) <= tol; };
  // Root of f in [a, b] where f(a), f(b) have opposite signs: the side of a.
  auto root_between = [&](auto&& f, double a, double fa, double b, double fb) {
    if (fa == 0.0) return a;
    std::uintmax_t iterations = 200;
    const auto bracket = boost::math::tools::toms748_solve(f, a, b, fa, fb, stop, iterations);
    return bracket.first;
  };
  // Root of guard k crossing downwards from t_pos (>= 0) to t_neg (< 0), on the >= 0 side.
  auto crossing = [&](int k, double t_pos, double g_pos, double t_neg, double g_neg) {
    return root_between([&](double t) { return guard(k, t); }, t_pos, g_pos, t_neg, g_neg);
  };
  auto extremum = [&](int k, double t0, double r0, double t1, double r1) {
    return root_between([&](double t) { return rate(k, t); }, t0, r0, t1, r1);
  };

  double t_lo = ta;
  Values g_lo = g_a, r_lo = r_a, g_s{}, r_s{};
  const int samples = std::max(settings.samples, 0);
  for (int s = 1; s <= samples + 1; ++s) {
    const double ts = s == samples + 1 ? tb : ta + (tb - ta) * double(s) / (samples + 1);
    state_at(ts, xs);
    sys.guard_values(ts, xs, g_s, &r_s);
    std::array<double, 2 * S::nc + 1> root;
    root.fill(std::numeric_limits<double>::quiet_NaN());
    bool any = false;
    for (int k = 0; k < n_guards; ++k) {
      const bool touchdown = sys.guards()[k].kind == GuardKind::Touchdown;
      if (g_lo[k] >= 0.0 && g_s[k] < 0.0) {
        // Case 1. A touchdown guard within the tolerance below zero and rising at t_s is the
        // integration error of a contact that is leaving (a gap of +1e-17 after a lift-off, -1e-11
        // one step later at rtol 1e-8), not an approach: it is left to case 3 if it goes down.
        if (touchdown && g_s[k] >= -settings.gap_tolerance && r_s[k] >= 0.0) continue;
        root[k] = crossing(k, t_lo, g_lo[k], ts, g_s[k]);
      } else if (touchdown && g_lo[k] >= 0.0 && g_s[k] >= 0.0 && r_lo[k] < 0.0 && r_s[k] > 0.0) {
        const double t_m = extremum(k, t_lo, r_lo[k], ts, r_s[k]);  // case 2
        const double g_m = guard(k, t_m);
        if (g_m < -settings.dip_depth) root[k] = crossing(k, t_lo, g_lo[k], t_m, g_m);
      } else if (touchdown && g_lo[k] < 0.0 && g_s[k] < -settings.gap_tolerance && g_s[k] < g_lo[k]) {
        if (r_lo[k] > 0.0 && r_s[k] < 0.0) {  // case 3
          const double t_max = extremum(k, t_lo, r_lo[k], ts, r_s[k]);
          const double g_max = guard(k, t_max);
          root[k] = g_max >= 0.0 ? crossing(k, t_max, g_max, ts, g_s[k]) : t_max;
        } else {
          root[k] = t_lo;
        }
      }
      any = any || std::isfinite(root[k]);
    }
    if (any) {
      double first = std::numeric_limits<double>::infinity();
      for (int k = 0; k < n_guards; ++k)
        if (std::isfinite(root[k])) first = std::min(first, root[k]);
      end.t_first_crossing = first;
      for (int k = 0; k < n_guards; ++k)
        end.fired[k] = std::isfinite(root[k]) && std::abs(root[k] - first) <= settings.simultaneity;
      return true;
    }
    t_lo = ts;
    g_lo = g_s;
    r_lo = r_s;
  }
  g_a = g_lo;
  r_a = r_lo;
  return false;
}

}  // namespace saltus::detail
