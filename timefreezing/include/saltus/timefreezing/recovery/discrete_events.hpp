// What a discrete time-freezing solution says happened, read off its FESD points: the frozen
// phases (impacts: the clock stands still while the auxiliary dynamics act, time-freezing Theorem
// 5) and the element boundaries where a switching function changes its active set (touchdowns into
// sliding, lift-offs, slip-stick).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <vector>

namespace saltus::timefreezing {

/// A frozen phase of the discrete solution: the clock stands still from tau_begin to tau_end,
/// the physical time is `time`, the state jumps from x_minus to x_plus (an impact).
template <int nx>
struct FrozenPhase {
  double tau_begin = 0.0, tau_end = 0.0;
  double time = 0.0;                       ///< physical time of the jump [s]
  /// x_minus: the state at `time`; x_plus: the state at the end of the run of frozen elements,
  /// reached at physical time time + clock_advance.
  Eigen::Matrix<double, nx, 1> x_minus, x_plus;
  /// The clock's advance over the run [s]: 0 when the clock stood still in every element; positive
  /// when an element of the run ran it: its last element's last stage (detail::element_frozen:
  /// the element goes on past the end of the impact, e.g. sliding), or an element whose clock
  /// crept while the impact acted (rate below detail::impact_clock_rate). x_plus is then that much
  /// later than the jump, not the post-impact state at `time`.
  double clock_advance = 0.0;
  /// True when the run of frozen elements ended before its impact did: at x_plus a contact still
  /// approaches (gap <= 1e-4 m and J_n v < -1e-4 m/s, recover_trajectory's tolerances), so x_plus
  /// is not the impact's outcome. The impact then goes on in the next, flowing element (the
  /// recovered trajectory's impact event reads x+ where it ends: recover_trajectory) or past the
  /// horizon's end. Set by simulate_time_freezing (read_events leaves it false: it has no scene).
  bool cut = false;
};

/// An element boundary where switching function m changes its active set (alpha rounded to
/// {0, 1/2, 1} differs between the elements on both sides).
struct SwitchPoint {
  double tau = 0.0;   ///< numerical time of the boundary
  double time = 0.0;  ///< physical time there
  int switching_function = 0;  ///< m = 3 i + (0: gap, 1: normal velocity, 2: tangential velocity)
  double alpha_before = 0.0, alpha_after = 0.0;  ///< mean alpha_m over the elements on both sides
};

namespace detail {
/// An element takes part in a frozen phase when its clock stands still (advance below
/// frozen_tolerance * h) or, with n_s >= 2, when its first stage is frozen (Theta < 1e-6): at the
/// end of an impact the element's last stage sits on the switching surfaces (gap = 0, J_n v = 0),
/// where both multipliers vanish and the step function, hence Theta and the clock there, is not
/// determined by the complementarity; the clock then advances by h b_ns Theta_ns inside an
/// element that is an impact (measured: 0.008 s for a dropped mass, a_n = 100). Such an element
/// still ends the frozen run.
/// Also frozen: an element whose clock runs at less than impact_clock_rate of the numerical rate
/// (advance < 1e-4 h) while its velocities jump (some |v| changes by more than 1 % of the largest
/// |v| at its ends, and by more than 1e-6): time-freezing's clock rate is 1 in flight and
/// a_n / (a_n + g)-like in a stance, so such an element is an impact whose clock crept a little
/// (measured: the plank-box's optimal inputs re-integrated on 32 elements per control interval,
/// 480 in all, h ~ 3.1e-3: an element that ran the clock 3.4e-9 s, rate 1.1e-6, above the frozen
/// tolerance's 1e-7, while the box's rate jumped by 1.035 rad/s; read as flowing, its end put a
/// post-impact state among the flow samples, 1.04 from the re-simulation). The velocity jump
/// keeps slow but smooth elements flowing.
inline constexpr double impact_clock_rate = 1e-4;
/// An element of numerical length h <= degenerate_element_length (1 + |tau|) is one FESD collapsed
/// to a point (h's lower bound is 0). recover_trajectory skips it: it has no mode (its step
/// functions are not determined by anything) and no impact fits in it (the auxiliary field
/// changes a velocity by at most a_n s h, 2.5e-8 m/s for a_n = 50 and s = 5), whereas the frozen
/// rule (advance <= frozen_tolerance h) holds trivially there and read it as an impact with no
/// guard and no velocity change (measured: an optimum of the plank-box short landing has two
/// elements of 1.0e-15 and 1.9e-15 at its lift-off; the first was read so). recover_reference
/// keeps such an element as before (frozen when its clock stands, its end a sample): its samples
/// are the re-simulation's input breakpoints, and dropping them turned the plank-box flagship's
/// simulated lift-off into two events 4e-14 s apart (measured); an empty event in the reference
/// costs nothing there.
inline constexpr double degenerate_element_length = 1e-10;
template <int ny, int nsw, int nu>
bool element_degenerate(const std::vector<FesdPoint<ny, nsw, nu>>& pts, int stages, int e) {
  const auto& start = e == 0 ? pts[0] : pts[static_cast<std::size_t>(e * stages)];
  const auto& end = pts[static_cast<std::size_t>((e + 1) * stages)];
  return !(end.tau - start.tau > degenerate_element_length * (1.0 + std::abs(end.tau)));
}
template <int ny, int nsw, int nu>
bool element_frozen(const std::vector<FesdPoint<ny, nsw, nu>>& pts, int stages, int e, double frozen_tolerance) {
  const auto& start = e == 0 ? pts[0] : pts[static_cast<std::size_t>(e * stages)];
  const auto& end = pts[static_cast<std::size_t>((e + 1) * stages)];
  const double h = end.tau - start.tau;
  if (!(h > 0.0)) return false;
  constexpr int clock = ny - 2 - nsw / 3;  // y = (q, v, t, L, g) with nc = nsw / 3 integrated gaps
  const double advance = end.y[clock] - start.y[clock];
  if (advance <= frozen_tolerance * h) return true;
  if (stages >= 2 && pts[static_cast<std::size_t>(1 + e * stages)].ode_weight < 1e-6) return true;
  if (advance < impact_clock_rate * h) {
    constexpr int nv = (clock) / 2;  // y = (q, v, ...) with nq = nv
    const auto v0 = start.y.template segment<nv>(nv), v1 = end.y.template segment<nv>(nv);
    const double jump = (v1 - v0).cwiseAbs().maxCoeff();
    return jump > 1e-6 && jump > 1e-2 * std::max(v0.cwiseAbs().maxCoeff(), v1.cwiseAbs().maxCoeff());
  }
  return false;
}
}  // namespace detail

namespace detail {
/// Reads frozen phases and switch points off a FESD solution (see TimeFreezingSimulation).
/// Frozen elements: detail::element_frozen.
template <int ny, int nsw, int nu, int nx>
void read_events(const std::vector<FesdPoint<ny, nsw, nu>>& pts, int stages, std::vector<double>& lengths,
                 std::vector<FrozenPhase<nx>>& frozen, std::vector<SwitchPoint>& switches, double frozen_tolerance = 1e-7) {
  const int clock = nx;
  const int elements = static_cast<int>((pts.size() - 1) / stages);
  auto start_of = [&](int e) -> const FesdPoint<ny, nsw, nu>& { return e == 0 ? pts[0] : pts[e * stages]; };
  auto end_of = [&](int e) -> const FesdPoint<ny, nsw, nu>& { return pts[(e + 1) * stages]; };
  std::vector<bool> is_frozen(elements);
  for (int e = 0; e < elements; ++e) {
    const double h = end_of(e).tau - start_of(e).tau;
    lengths.push_back(h);
    is_frozen[e] = element_frozen(pts, stages, e, frozen_tolerance);
  }
  for (int e = 0; e < elements;) {
    if (!is_frozen[e]) {
      ++e;
      continue;
    }
    int f = e;
    while (f + 1 < elements && is_frozen[f + 1]) ++f;
    FrozenPhase<nx> p;
    p.tau_begin = start_of(e).tau;
    p.tau_end = end_of(f).tau;
    p.time = start_of(e).y[clock];
    p.x_minus = start_of(e).y.template head<nx>();
    p.x_plus = end_of(f).y.template head<nx>();
    p.clock_advance = end_of(f).y[clock] - p.time;
    frozen.push_back(p);
    e = f + 1;
  }
  auto mean_alpha = [&](int e, int m) {
    double s = 0.0;
    for (int r = 0; r < stages; ++r) s += pts[1 + e * stages + r].alpha[m];
    return s / stages;
  };
  auto rounded = [](double a) { return a > 1.0 - 1e-6 ? 2 : (a < 1e-6 ? 0 : 1); };
  for (int e = 0; e + 1 < elements; ++e)
    for (int m = 0; m < nsw; ++m) {
      const double a = mean_alpha(e, m), b = mean_alpha(e + 1, m);
      if (rounded(a) != rounded(b)) switches.push_back({end_of(e).tau, end_of(e).y[clock], m, a, b});
    }
}
}  // namespace detail

}  // namespace saltus::timefreezing
