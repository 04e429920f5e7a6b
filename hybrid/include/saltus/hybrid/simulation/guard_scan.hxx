// The event search over one accepted step, shared by both backends (integrator_dopri.hxx,
// integrator_cvode.hxx). Internal header: included by definition files only.
//
// A guard gamma_k is checked at the step's end and at `samples` interior points of the step's
// continuous extension x(t); between consecutive check points [t_lo, t_s] a guard fires when
//  1. it crosses: gamma(t_lo) >= 0 > gamma(t_s) (every guard kind); the event time is the root,
//     located by TOMS 748 on the extension, on its >= 0 side (the last instant of the mode). A
//     touchdown that ends within gap_tolerance below zero while rising is not an approach (the
//     integration error of a contact that leaves the surface) and does not fire. A touchdown that
//     starts within gap_tolerance of the surface is searched for its maximum first (Brent's
//     method): a contact opened with a tiny separating acceleration that rises and returns
//     within the interval touches at its return, not at t_lo;
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
//  4. any other guard (release, stop, slip onset: functions of the contact force or of the
//     tangential velocity, with no cheap exact rate) dips below zero and back between check
//     points. These guards depend on the input, which the integrator's error control does not
//     see: at rest on a table the flow is constant and the steps grow past the time scale of
//     the input, so a normal force that goes below zero and back within one step would be
//     missed (a silently wrong trajectory: no release). The samples of the step tell where a
//     minimum can hide: an interior check point lower than both neighbours (the minimum is
//     within the two intervals around it), or a step end lower than its neighbour where the
//     parabola through the three nearest check points has its vertex in the end interval. Where
//     such a sampled minimum is within dip_reach times the local variation of the samples of
//     zero, Brent's method locates the true minimum on that bracket; below
//     -dip_relative * max |gamma_k| at the check points, the crossing is located between the
//     bracket's left end and the minimum. A dip that no check point sees (narrower than the
//     spacing of the check points) stays invisible: raise guard_samples or limit max_step.
// Cases 2 and 3 make the step's post-condition an invariant: no open contact ends an accepted
// step below -gap_tolerance unless it started the step lower still (the drift of a contact
// released below the surface, which rises).
#pragma once

#include <boost/math/tools/minima.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <saltus/hybrid/vocabulary/errors.hpp>
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
  /// Case 4: a sampled minimum of a non-touchdown guard is searched when it is within dip_reach
  /// times the variation of the samples around it of zero...
  double dip_reach = 8.0;
  /// ...and it fires when the minimum is below -dip_relative * max |gamma_k| at the check points
  /// (a minimum at zero up to round-off is a grazing motion and fires nothing).
  double dip_relative = 1e-10;

  /// Most interior check points per step (the samples of a step live on the stack).
  static constexpr int max_samples = 14;

  /// The settings of a backend's options and the simulator's tolerances.
  /// @throws InvalidArgument if options.guard_samples is outside [0, max_samples].
  static GuardScanSettings of(const IntegratorOptions& options, double gap_tolerance, double simultaneity) {
    if (options.guard_samples < 0 || options.guard_samples > max_samples)
      throw InvalidArgument("IntegratorOptions::guard_samples = " + std::to_string(options.guard_samples) +
                            " is outside [0, " + std::to_string(max_samples) + "]");
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

  // All check points of the step first: case 4 looks at a check point's neighbours on both sides.
  const int m = settings.samples + 1;  // check points after ta; t_0 = ta, t_m = tb
  std::array<double, GuardScanSettings::max_samples + 2> tk;
  std::array<Values, GuardScanSettings::max_samples + 2> gk, rk;
  tk[0] = ta;
  gk[0] = g_a;
  rk[0] = r_a;
  for (int s = 1; s <= m; ++s) {
    tk[s] = s == m ? tb : ta + (tb - ta) * double(s) / m;
    state_at(tk[s], xs);
    sys.guard_values(tk[s], xs, gk[s], &rk[s]);
  }
  // Case 4 on the bracket [a, b] of guard k: the root, or NaN when the minimum is not below zero.
  auto dip = [&](int k, double a, double ga, double b, double scale) {
    const auto [t_min, g_min] =
        boost::math::tools::brent_find_minima([&](double t) { return guard(k, t); }, a, b, 30);
    if (!(g_min < -settings.dip_relative * scale)) return std::numeric_limits<double>::quiet_NaN();
    return crossing(k, a, ga, t_min, g_min);
  };
  // Vertex of the parabola through (t0, g0), (t1, g1), (t2, g2), or NaN if it is not convex.
  auto vertex = [](double t0, double g0, double t1, double g1, double t2, double g2) {
    const double d01 = (g1 - g0) / (t1 - t0), d12 = (g2 - g1) / (t2 - t1), curvature = (d12 - d01) / (t2 - t0);
    if (!(curvature > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    return 0.5 * (t0 + t1) - d01 / (2.0 * curvature);
  };
  constexpr double round_off = 64.0 * std::numeric_limits<double>::epsilon();

  for (int s = 1; s <= m; ++s) {
    const double t_lo = tk[s - 1], ts = tk[s];
    const Values &g_lo = gk[s - 1], &r_lo = rk[s - 1], &g_s = gk[s], &r_s = rk[s];
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
        double t_from = t_lo, g_from = g_lo[k];
        if (touchdown && g_lo[k] <= settings.gap_tolerance) {
          // A contact that starts on the surface (opened at this instant, with a tiny separating
          // acceleration) may rise and come back within the interval: the crossing is the return,
          // after the gap's maximum, not t_lo where the gap is zero (which would end the segment
          // where it starts, and the event would open the contact again: a stall).
          const auto [t_max, minus_g] =
              boost::math::tools::brent_find_minima([&](double t) { return -guard(k, t); }, t_lo, ts, 30);
          if (-minus_g > g_lo[k] && t_max < ts) {
            t_from = t_max;
            g_from = -minus_g;
          }
        }
        root[k] = crossing(k, t_from, g_from, ts, g_s[k]);
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
      } else if (!touchdown && m >= 2 && g_lo[k] >= 0.0 && g_s[k] >= 0.0) {
        // Case 4, on the brackets that end at t_s (the earlier check points are clear of roots).
        double scale = 0.0;
        for (int j = 0; j <= m; ++j) scale = std::max(scale, std::abs(gk[j][k]));
        const double noise = round_off * scale;
        if (s >= 2 && gk[s - 2][k] >= 0.0 && g_lo[k] <= gk[s - 2][k] && g_lo[k] <= g_s[k]) {
          // t_lo is a sampled minimum: the true one is in [t_{s-2}, t_s] (its left end >= 0, so
          // that the crossing is bracketed: a guard that starts the step at round-off below zero
          // is not searched from there).
          const double variation = std::max(gk[s - 2][k], g_s[k]) - g_lo[k];
          if (variation > noise && g_lo[k] <= settings.dip_reach * variation)
            root[k] = dip(k, tk[s - 2], gk[s - 2][k], ts, scale);
        }
        const bool first = s == 1 && g_lo[k] < g_s[k], last = s == m && g_s[k] < g_lo[k];
        if (!std::isfinite(root[k]) && (first || last)) {
          // A step end is the sampled minimum: search the end interval if the parabola through
          // the three nearest check points has its vertex there.
          const int j0 = first ? 0 : m - 2;
          const double tv = vertex(tk[j0], gk[j0][k], tk[j0 + 1], gk[j0 + 1][k], tk[j0 + 2], gk[j0 + 2][k]);
          const double g_end = first ? g_lo[k] : g_s[k];
          const double variation = std::abs(g_s[k] - g_lo[k]);
          if (tv > t_lo && tv < ts && variation > noise && g_end <= settings.dip_reach * variation)
            root[k] = dip(k, t_lo, g_lo[k], ts, scale);
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
  }
  g_a = gk[m];
  r_a = rk[m];
  return false;
}

}  // namespace saltus::detail
