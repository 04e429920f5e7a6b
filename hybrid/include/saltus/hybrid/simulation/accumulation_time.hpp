// The accumulation time of a sequence of touchdown times, extrapolated by Aitken's process applied
// twice (simulator.hpp's file comment says why and when), with the derivative of the extrapolated
// time with respect to each touchdown time it uses, and its uncertainty in two parts
// (HybridTrajectory::zeno_time_uncertainty): the extrapolation's own, and the touchdown times' error
// from the integration that the extrapolation carries into it.
//
// The integration part. Let s_k be the located touchdown times (k = 0 the last), e_k their errors,
// t = Z(s_0, ..., s_n) the extrapolation (n = 4 period). To first order the error of t is
//     sum_k (dZ/ds_k) e_k = e_0 + sum_k (dZ/ds_k) (e_k - e_0)        (sum_k dZ/ds_k = 1, translation)
// The sensitivities are large (sum_k |dZ/ds_k| = 7 for a bouncing ball with e_n = 0.5, 32 for a
// spoked wheel, 2600 for a rocking block with Housner's ratio 0.85: the iterated process divides by
// second differences of the intervals), so that bounding each e_k alone and summing
// |dZ/ds_k| |e_k| overstates the error by that factor. But the e_k are not independent: each is the
// phase error the integration accumulated since the run started (or since the last accumulation
// it was continued past), nearly all of it before the accumulation's last few, short flights. So e_k
// is a common shift e_0 plus differences e_k - e_0 of the size of the error made over the last
// few intervals, and e_0 passes into t one to one. Measured against closed forms
// (tests/test_accumulation.cpp, AccumulationTable): where the extrapolation's own error is the
// smaller (a rocking block detected after 40 ratios, a spoked wheel), |t - t_inf| is within 8 % of
// |e_0|, while sum_k |dZ/ds_k| |e_k| is 30 (the wheel) to 2700 (the block) times |e_0|.
//
// e_0 is the phase error of an integration over T = s_0 - t_start with relative tolerance rho: the
// integrator keeps the local error of every step within rho of the state, which makes the
// motion's time scale wrong by a relative amount of order rho, and its phase by rho T. Measured
// (Dormand-Prince, relative tolerance 1e-12 to 1e-8): |e_0| / (rho T) = 1.3 to 2.1 for a block
// rocking after a fall from rest (the fall from the unstable tilt amplifies the state's error),
// 0.8 to 0.9 for a ball on a spring, 0.09 to 0.7 for a spoked wheel; polynomial flights (a ball
// or a box in free fall) are integrated exactly and err by round-off only. So the bound is
//     drift_factor rho T,   rho = relative_tolerance + absolute_tolerance / state_scale,
// with drift_factor = 4 (a margin of 1.9 over the worst measured ratio); state_scale (the largest
// |x_i| at the touchdowns, in the state's units) turns the absolute tolerance into a relative one
// where it dominates. To it are added the event location, root_tolerance max(1, |s_k|) on every
// touchdown, carried through the sensitivities (sum_k |dZ/ds_k| root_tolerance max(1, |s_k|): no
// common shift there, each root is located alone), and the uncertainty of the accumulation time
// the run was continued from, if any (it shifts every later touchdown one to one).
//
// It does not cover: motions that amplify a state error over the run by more than the measured
// factors (chaotic motion, a long wait near an unstable equilibrium): there the touchdown times
// are not determined to rho T by the data, and no bound from the tolerances alone holds; and the
// CVODE backends (BDF, Adams), whose touchdown times under the same tolerances were measured up to
// 3200 rho T off (the same closed forms; CVODE's error does not shrink in proportion to its
// tolerances): the bound would not hold there (a rocking block at the default tolerances: 1.7e-7 s
// off against 2.6e-8 s), so the simulator states an infinite integration part for them.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>

namespace saltus {

struct AccumulationTime {
  /// Touchdown times an extrapolation uses at most: 4 periods of 2 and the last touchdown.
  static constexpr int max_times = 9;
  /// s: the extrapolated accumulation time.
  double t = std::numeric_limits<double>::quiet_NaN();
  /// s: the extrapolation's own uncertainty (simulator.hpp): twice the change of the second order
  /// over the last period, or the change between the orders; infinite for the geometric estimate.
  double extrapolation_uncertainty = std::numeric_limits<double>::infinity();
  /// dt / ds_k (dimensionless) for s_k = times[m - 1 - k], k < used (the last touchdown first);
  /// they sum to 1 (a common shift of the touchdown times shifts t one to one).
  std::array<double, max_times> sensitivity{};
  int used = 0;
};

/// The integration part's factor on rho T (file comment).
inline constexpr double touchdown_drift_factor = 4.0;

/// s: the integration part of the accumulation time's uncertainty (file comment), from the
/// extrapolation `a` of the touchdown times `times` (ascending, those given to
/// extrapolate_accumulation_time): touchdown_drift_factor (relative_tolerance + absolute_tolerance /
/// state_scale) (s_0 - t_start) + sum_k |dZ/ds_k| root_tolerance max(1, |s_k|) + carried.
/// relative_tolerance, absolute_tolerance, root_tolerance as in IntegratorOptions; state_scale > 0
/// the largest |x_i| at the touchdowns (state units); t_start (s) the start of the run or of the
/// motion after the last accumulation the run was continued past; carried (s) that accumulation
/// time's uncertainty (0 without one).
inline double touchdown_integration_uncertainty(const AccumulationTime& a, std::span<const double> times,
                                                double relative_tolerance, double absolute_tolerance,
                                                double state_scale, double root_tolerance, double t_start,
                                                double carried) {
  const int m = static_cast<int>(times.size());
  const double rho = relative_tolerance + (state_scale > 0 ? absolute_tolerance / state_scale : 0.0);
  double location = 0.0;
  for (int k = 0; k < a.used; ++k)
    location += std::abs(a.sensitivity[k]) * root_tolerance * std::max(1.0, std::abs(times[m - 1 - k]));
  return touchdown_drift_factor * rho * std::max(0.0, times[m - 1] - t_start) + location + carried;
}

namespace detail {
/// A value and its gradient with respect to the last AccumulationTime::max_times touchdown times.
struct TimeAndGradient {
  double v = 0.0;
  std::array<double, AccumulationTime::max_times> d{};
  friend TimeAndGradient operator-(TimeAndGradient a, const TimeAndGradient& b) {
    a.v -= b.v;
    for (std::size_t k = 0; k < a.d.size(); ++k) a.d[k] -= b.d[k];
    return a;
  }
  /// a - b^2 / c (the step of Aitken's process) with its gradient.
  static TimeAndGradient minus_square_over(TimeAndGradient a, const TimeAndGradient& b, const TimeAndGradient& c) {
    const double q = b.v / c.v;
    a.v -= b.v * b.v / c.v;
    for (std::size_t k = 0; k < a.d.size(); ++k) a.d[k] -= 2.0 * q * b.d[k] - q * q * c.d[k];
    return a;
  }
};
}  // namespace detail

/// The accumulation time of the touchdown times `times` (ascending) of an accumulation of period
/// `period` (1: one ratio between consecutive intervals; 2: between intervals two apart) and mean
/// interval ratio `ratio` < 1 (simulator.hpp): Aitken's process applied twice to the touchdowns
/// `period` apart when 4 period + 1 of them are given, else the geometric estimate (the remaining
/// intervals continue the last period with the ratio), with an infinite extrapolation uncertainty.
/// @pre times.size() >= period + 1, period in {1, 2}.
inline AccumulationTime extrapolate_accumulation_time(std::span<const double> times, int period, double ratio) {
  using detail::TimeAndGradient;
  const int m = static_cast<int>(times.size());
  AccumulationTime out;
  // The geometric estimate: t = s_0 + (s_0 - s_p) r / (1 - r), the ratio held fixed.
  const double q = ratio / (1.0 - ratio);
  out.t = times[m - 1] + (times[m - 1] - times[m - 1 - period]) * q;
  out.used = period + 1;
  out.sensitivity[0] = 1.0 + q;
  out.sensitivity[period] = -q;
  if (m < 4 * period + 1) return out;  // too few touchdowns for two orders of Aitken's process
  // The touchdowns `period` apart, s(0) the last: s(j) = times[m - 1 - period j].
  auto s = [&](int back) {
    TimeAndGradient x;
    x.v = times[m - 1 - period * back];
    x.d[period * back] = 1.0;
    return x;
  };
  // Aitken's delta-squared from s2, s1, s0: s0 - (s0 - s1)^2 / ((s0 - s1) - (s1 - s2)), exact for a
  // geometric tail; s0 where the second difference vanishes.
  auto aitken = [](const TimeAndGradient& s2, const TimeAndGradient& s1, const TimeAndGradient& s0) {
    const TimeAndGradient d1 = s0 - s1, d0 = s1 - s2;
    return d1.v == d0.v ? s0 : TimeAndGradient::minus_square_over(s0, d1, d1 - d0);
  };
  const TimeAndGradient a0 = aitken(s(2), s(1), s(0)), a1 = aitken(s(3), s(2), s(1)), a2 = aitken(s(4), s(3), s(2));
  const TimeAndGradient iterated = aitken(a2, a1, a0);  // the second order
  const double last = times[m - 1];
  if (!std::isfinite(a0.v) || !std::isfinite(iterated.v) || a0.v < last || iterated.v < last) return out;
  out.t = iterated.v;
  out.used = 4 * period + 1;
  out.sensitivity = iterated.d;
  // Twice the change of the second order over the last period where a period more was recorded
  // (it converges at least geometrically: the change bounds its error; measured on balls on springs,
  // tests/test_accumulation.cpp: error 0.5 and 0.55 of the change), else the change between the
  // orders (an estimate of the first order's error, larger than the second's).
  if (m >= 5 * period + 1) {
    auto sv = [&](int back) { return times[m - 1 - period * back]; };
    auto aitken_value = [](double s2, double s1, double s0) {
      const double d1 = s0 - s1, d0 = s1 - s2;
      return d1 == d0 ? s0 : s0 - d1 * d1 / (d1 - d0);
    };
    const double a3 = aitken_value(sv(5), sv(4), sv(3));
    const double previous = aitken_value(a3, a2.v, a1.v);
    if (std::isfinite(previous)) {
      out.extrapolation_uncertainty = 2.0 * std::abs(iterated.v - previous);
      return out;
    }
  }
  out.extrapolation_uncertainty = std::abs(iterated.v - a0.v);
  return out;
}

}  // namespace saltus
