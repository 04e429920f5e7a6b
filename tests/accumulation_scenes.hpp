// Test-local scenes and references of tests/test_accumulation.cpp for accumulations of impacts that
// alternate between two support points: a spoked (rimless) wheel settling on two spokes, and the
// reference for every planar body rocking between two support points on flat ground (Housner's
// rocking block, the spoked wheel), from the exact per-impact map.
#pragma once

#include "support.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace saltus::testing {

/// A spoked (rimless) wheel in the vertical plane: a rigid hub (mass m, moment of inertia I_c about
/// the hub, the centre of mass) with N massless spokes of length L, q = (x, y, theta) the hub's
/// position and the wheel's angle (counter-clockwise). Spoke i points along theta + 2 pi i / N from
/// the downward vertical: its tip is (x + L sin(phi_i), y - L cos(phi_i)), phi_i = theta + 2 pi i / N,
/// a planar Coulomb contact with the flat ground y = 0 (friction mu, restitution e). No inputs.
struct SpokedWheel {
  static constexpr int N = 6;
  static constexpr int nq = 3, nu = 0, nc = N;
  static constexpr double g = 9.81;
  double m = 1.0, I_c = 0.05, L = 0.5;
  std::array<ContactSpec, N> tips;
  SpokedWheel(double mu, double e)
      : tips{ContactSpec{"spoke 0", Friction::Planar, mu, e}, ContactSpec{"spoke 1", Friction::Planar, mu, e},
             ContactSpec{"spoke 2", Friction::Planar, mu, e}, ContactSpec{"spoke 3", Friction::Planar, mu, e},
             ContactSpec{"spoke 4", Friction::Planar, mu, e}, ContactSpec{"spoke 5", Friction::Planar, mu, e}} {}
  const ContactSpec& contact(int i) const { return tips[i]; }
  template <class T>
  MatT<T, 3, 3> mass_matrix(const VecT<T, 3>&) const {
    MatT<T, 3, 3> M = MatT<T, 3, 3>::Identity() * T(m);
    M(2, 2) = T(I_c);
    return M;
  }
  template <class T>
  VecT<T, 3> bias(const VecT<T, 3>&, const VecT<T, 3>&) const {
    return VecT<T, 3>(T(0), T(m * g), T(0));
  }
  template <class T>
  MatT<T, 3, 0> input_matrix(const VecT<T, 3>&) const {
    return {};
  }
  template <class T>
  VecT<T, 2> tip(int i, const VecT<T, 3>& q) const {
    using std::cos;
    using std::sin;
    const T phi = q[2] + 2.0 * std::numbers::pi * i / N;
    return VecT<T, 2>(q[0] + L * sin(phi), q[1] - L * cos(phi));
  }
  template <class T>
  T gap(int i, const VecT<T, 3>& q) const {
    return tip(i, q)[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, 3>& q) const {
    return VecT<T, 2>(tip(i, q)[0], T(0));
  }
  /// Half the angle between neighbouring spokes: the angle of each support spoke from the vertical
  /// in double support.
  static constexpr double alpha() { return std::numbers::pi / N; }
  /// Standing on spoke 0, its tip at the origin, the hub at the angle psi from the vertical above
  /// the tip (psi > 0: ahead of it, towards +x), turning over the tip at psi' = dpsi (> 0: forward,
  /// clockwise). The hub is L (sin psi, cos psi), spoke 0 points along -psi (theta = -psi), and the
  /// tip's velocity is zero.
  Vec<6> standing_on_spoke_0(double psi, double dpsi) const {
    Vec<6> x;
    x << L * std::sin(psi), L * std::cos(psi), -psi, dpsi * L * std::cos(psi), -dpsi * L * std::sin(psi), -dpsi;
    return x;
  }
};

/// Gauss-Legendre nodes and weights on [0, 1] (Newton's iteration on the Legendre recurrence).
inline std::vector<std::array<double, 2>> gauss_legendre_01(int n) {
  std::vector<std::array<double, 2>> rule;
  for (int i = 0; i < n; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p1 = 1.0, p0 = 0.0;
      for (int j = 1; j <= n; ++j) {
        const double pm = p0;
        p0 = p1;
        p1 = ((2.0 * j - 1.0) * z * p0 - (j - 1.0) * pm) / j;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    rule.push_back({0.5 * (1.0 + z), 1.0 / ((1.0 - z * z) * dp * dp)});  // weight 2 / (...) halved
  }
  return rule;
}

/// A planar rigid body (mass m, moment of inertia I_c about its centre of mass G) rocking between
/// two support points O and O' on flat ground, 2 R sin(alpha) apart, each at distance R from G,
/// with G above their middle in double support (G - O at the angle alpha from the vertical):
/// Housner's rocking block (R the half-diagonal, alpha = atan(w / h)) and the spoked wheel (R = L,
/// alpha = pi / N). The supports stick (no slip) and the impacts are plastic (e_n = 0).
///
/// Between impacts the body turns about one support: with psi the angle of O -> G from the
/// vertical (psi = alpha in double support, towards the other support), I_O = I_c + m R^2 and
///     I_O psi'' = m g R sin(psi),   p^2 = m g R / I_O                    (an inverted pendulum)
/// whose energy integral is psi'^2 = psi_0'^2 + 2 p^2 (cos(psi_0) - cos(psi)).
///
/// Fall (the rocking half-cycle). From rest at psi = alpha - A (amplitude A, the tilt from double
/// support) to the impact at psi = alpha:
///     T(A) = int_{alpha - A}^{alpha} dpsi / sqrt(2 p^2 (cos(alpha - A) - cos(psi))),
/// an incomplete elliptic integral of the first kind. With psi = alpha - A u^2 (u in [0, 1]) and
/// cos(a) - cos(b) = 2 sin((a + b) / 2) sin((b - a) / 2):
///     T(A) = int_0^1 2 A u du / sqrt(4 p^2 sin(alpha - A + A u^2 / 2) sin(A u^2 / 2)),
/// whose integrand is analytic on [0, 1] (u / sqrt(sin(A u^2 / 2)) is; the nearest singularity is at
/// u = i sqrt(2 (alpha - A) / A), far off the interval for A < alpha / 2), so that Gauss-Legendre
/// quadrature converges geometrically: 64 nodes reach round-off (checked against 48 nodes in the
/// tests, and against mpmath's quad at 40 digits: both tests' t_inf to 1e-15). The impact
/// speed is psi'^2 = 2 p^2 (cos(alpha - A) - cos(alpha)) = 4 p^2 sin(alpha - A / 2) sin(A / 2), and
/// a launch at speed w from double support reaches the amplitude A with
/// 4 p^2 sin(alpha - A / 2) sin(A / 2) = w^2 (solved by Newton's method, without cancellation for
/// small A). The rise to A after an impact takes T(A) as well (time reversal), so the interval
/// between two impacts of the rocking is 2 T(A).
/// The linearised closed form, sin(psi) ~ psi: T(A) = acosh(alpha / (alpha - A)) / p, is off by
/// 6.5e-3 relative (8.2e-4 s) for the block's first fall (A = 0.05, alpha = 0.32), far above the
/// tolerances here: not used.
///
/// Vault. Turning over the top of a support from psi_0 (< 0, behind it) at psi_0' = w_0 > 0 until
/// the next support touches down at psi = alpha, when the energy suffices
/// (w_0^2 > 2 p^2 (1 - cos psi_0)):
///     T_v = int_{psi_0}^{alpha} dpsi / sqrt(w_0^2 + 2 p^2 (cos(psi_0) - cos(psi))),
/// a smooth integrand (Gauss-Legendre on [psi_0, alpha]), and the impact speed
/// w^2 = w_0^2 + 2 p^2 (cos(psi_0) - cos(alpha)).
///
/// The impact (plastic, the new support sticking). Before it the body turns about O at Omega^-;
/// after it about O' at Omega^+, and the old support O lifts off. The impulse acts at O', so the
/// angular momentum about O' is conserved:
///     H_O' = I_c Omega + m (G - O') x v_G,   v_G^- = Omega^- e_z x (G - O),  v_G^+ = Omega^+ e_z x (G - O'),
/// and (G - O') x (e_z x (G - O)) = e_z ((G - O') . (G - O)) = e_z R^2 cos(2 alpha) (the angle
/// between G - O and G - O' is 2 alpha), so I_c Omega^- + m R^2 cos(2 alpha) Omega^- = (I_c + m R^2)
/// Omega^+ and the per-impact ratio of the angular velocities is the constant
///     r = (I_c + m R^2 cos(2 alpha)) / (I_c + m R^2).
/// For a uniform block (I_c = m R^2 / 3): r = 3/4 (1/3 + 1 - 2 sin^2 alpha) = 1 - (3/2) sin^2(alpha),
/// Housner's ratio (G. W. Housner, "The behavior of inverted pendulum structures during
/// earthquakes", Bull. Seismol. Soc. Am. 53(2), 1963). It is the body's motion only if the old
/// support lifts off (its velocity after the impact, Omega^+ e_z x (O - O'), is normal to the ground
/// and upward: it is, Omega^+ has the sign of Omega^-) and the impulse P = m (v_G^+ - v_G^-) lies in
/// the friction cone: P_t / P_n = cot(alpha) (1 - r) / (1 + r) (0.24 for the block, 0.46 for the
/// wheel; mu = 2 in the tests). After the impact the body rocks back (no vault) if
/// (r w)^2 < 2 p^2 (1 - cos(alpha)), so each impact sends it back with r times the speed it came
/// with: the impact speeds w_k = r^k w_1 and the accumulation time is
///     t_inf = t_1 + sum_{k >= 1} 2 T(A(w_k)),            A(w): 4 p^2 sin(alpha - A / 2) sin(A / 2) = w^2,
/// (t_1, w_1: the first impact of the rocking and its speed), summed until the terms are below
/// round-off. The intervals 2 T(A(w_k)) shrink by r only in the limit: T is not proportional to
/// the speed at finite amplitude.
struct PivotRocking {
  double alpha, p2, r;
  /// The quadrature rule of fall() and vault(): Gauss-Legendre on [0, 1], 64 nodes unless set.
  std::vector<std::array<double, 2>> rule = gauss_legendre_01(64);
  void set_nodes(int n) { rule = gauss_legendre_01(n); }

  static PivotRocking of(double m, double I_c, double R, double alpha) {
    const double I_O = I_c + m * R * R;
    return PivotRocking{alpha, m * 9.81 * R / I_O, (I_c + m * R * R * std::cos(2 * alpha)) / I_O};
  }
  /// T(A): from rest at amplitude A to the impact.
  double fall(double A) const {
    double sum = 0.0;
    for (const auto& [u, w] : rule)
      sum += w * 2 * A * u / std::sqrt(4 * p2 * std::sin(alpha - A + 0.5 * A * u * u) * std::sin(0.5 * A * u * u));
    return sum;
  }
  /// The impact speed |psi'| after a fall from amplitude A.
  double impact_speed(double A) const { return std::sqrt(4 * p2 * std::sin(alpha - 0.5 * A) * std::sin(0.5 * A)); }
  /// The amplitude reached from double support at speed w (w below the vault speed).
  double amplitude(double w) const {
    const double c = w * w / (2 * p2);
    double A = alpha - std::acos(std::cos(alpha) + c);  // a start, inaccurate for small A
    if (!(A > 0)) A = c / std::sin(alpha);
    for (int it = 0; it < 8; ++it) A -= (2 * std::sin(alpha - 0.5 * A) * std::sin(0.5 * A) - c) / std::sin(alpha - A);
    return A;
  }
  /// The speed from double support that just reaches the top of the support (psi = 0).
  double vault_speed() const { return std::sqrt(2 * p2 * (1 - std::cos(alpha))); }
  /// T_v: from psi0 (< 0) at psi' = w0 over the top to the impact at psi = alpha.
  double vault(double psi0, double w0) const {
    double sum = 0.0;
    for (const auto& [u, w] : rule) {
      const double psi = psi0 + (alpha - psi0) * u;
      sum += w * (alpha - psi0) / std::sqrt(w0 * w0 + 2 * p2 * (std::cos(psi0) - std::cos(psi)));
    }
    return sum;
  }
  double vault_impact_speed(double psi0, double w0) const {
    return std::sqrt(w0 * w0 + 2 * p2 * (std::cos(psi0) - std::cos(alpha)));
  }
  /// The impacts of the rocking from its first one at t1 with speed w1: their times (the first
  /// `keep`) and the accumulation time t_inf.
  struct Impacts {
    std::vector<double> t;
    double t_inf = 0.0;
  };
  Impacts rocking(double t1, double w1, std::size_t keep = 40) const {
    Impacts out;
    out.t.push_back(t1);
    double t = t1, w = r * w1, tail = 0.0;
    for (int k = 0; k < 100000 && w > 1e-30 * w1; ++k, w *= r) {
      const double interval = 2 * fall(amplitude(w));
      if (out.t.size() < keep) {
        t += interval;
        out.t.push_back(t);
      } else {
        tail += interval;  // the intervals past the kept impacts
      }
    }
    out.t_inf = t + tail;
    return out;
  }
};

}  // namespace saltus::testing
