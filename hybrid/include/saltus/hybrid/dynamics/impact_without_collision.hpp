// Painleve's inconsistent configuration and its rigid-body resolution, the impact without collision
// (a tangential impact): Genot & Brogliato, "New results on Painleve paradoxes", Eur. J. Mech.
// A/Solids 18 (1999) 653-677 (the Darboux-Keller integration of the impulse at zero approach
// velocity: slip until the slip stops, then stick until the normal velocity is zero again).
//
// The configuration. One planar-friction contact, closed (gap 0, normal velocity v_n = 0),
// sliding with tangential velocity v_t != 0, s = sign(v_t). W = J M^{-1} J^T is its Delassus
// matrix, J stacking w_n^T and w_t^T (rows n, t), symmetric positive semidefinite. With the
// friction of the slip, lambda_t = -mu s lambda_n, the normal acceleration of the contact is
//     a_n = d lambda_n + b,    d = W_nn - mu s W_nt,    b = w_n^T a_free + kappa_n
// (a_free = M^{-1}(S u - h), kappa_n the curvature term). With d <= 0 and b < 0 no lambda_n >= 0
// gives a_n >= 0 (lambda_n = 0 penetrates, a positive force pulls the contact down harder): the
// acceleration-level contact problem has no solution. The simulator refuses such a state by
// default (ContactProblemFailure from the mode selection, InvalidArgument for a given initial mode).
//
// The resolution. An impulse at the contact's zero approach velocity: time does not advance, bounded
// forces (gravity, inputs) give no impulse, and the contact velocities (v_n, v_t) move with the
// impulse P = (P_n, P_t) as dv = W dP, with Coulomb's law on the increments and P_n (>= 0,
// increasing) as the parameter of the process (Darboux-Keller):
//  - phase 1, slip in the direction s: dP_t = -mu s dP_n, so
//        dv_n = (W_nn - mu s W_nt) dP_n = d dP_n <= 0   (the impulse itself compresses),
//        dv_t = (W_tn - mu s W_tt) dP_n = c dP_n;
//    the slip stops (v_t = 0) at P_n1 = -v_t / c, where v_n1 = v_n + d P_n1 <= v_n, P_t1 = -mu s P_n1.
//    It does stop: d <= 0 means mu s W_nt >= W_nn > 0, so s W_nt = |W_nt| and
//    mu >= W_nn / |W_nt| >= |W_nt| / W_tt (W_nn W_tt >= W_nt^2, W positive semidefinite); hence
//    s c = |W_tn| - mu W_tt <= 0, strictly where det W > 0 or d < 0.
//  - phase 2, at v_t = 0: stick keeps dv_t = W_tn dP_n + W_tt dP_t = 0, dP_t = -(W_tn / W_tt) dP_n,
//    inside the friction cone since |W_tn| / W_tt <= mu (the same inequality): stick is always
//    possible after the slip of an inconsistent configuration, and a reverse slip never happens. Then
//        dv_n = (W_nn - W_nt W_tn / W_tt) dP_n = (det W / W_tt) dP_n > 0,
//    and the impulse ends when the normal velocity is back to zero: P_n2 = -v_n1 W_tt / det W,
//    P_t2 = -(W_tn / W_tt) P_n2 (no expansion: the contact had no approach velocity to restore).
// Total: P = (P_n1 + P_n2, P_t1 + P_t2), the velocity jump v+ = v- + M^{-1} J^T P. Since both phases
// end with v_n = v_t = 0, P = -W^{-1} (v_n, v_t) (where det W > 0): the total is the stick impulse of
// the contact, the jump map of ImpulseRole::Stick (jump_map.hpp), and |P_t| <= mu P_n holds. The
// kinetic energy changes by (1/2) P^T (v- + v+) (contact coordinates) = -(1/2) v^T W^{-1} v < 0.
//
// The rod of tests/test_event_detection.cpp (uniform, 1 kg, 1 m, at 45 degrees, mu = 2, its end
// sliding at v_t = -1 m/s): W = [2.5, -1.5; -1.5, 2.5] 1/kg, d = -1/2, c = 7/2; P_n1 = 2/7,
// P_t1 = 4/7, v_n1 = -1/7 m/s; P_n2 = 5/56, P_t2 = 3/56; P = (3/8, 5/8) N s; kinetic energy
// 0.5 J -> 0.1875 J.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <saltus/hybrid/vocabulary/errors.hpp>

namespace saltus {

/// What the event-driven simulator does with a closed sliding contact that has no consistent
/// acceleration-level contact mode (Painleve's inconsistent configuration, file comment).
/// - Refuse (the default): the run throws (ContactProblemFailure from the mode selection;
///   InvalidArgument where the inconsistent slip is given as the initial mode).
/// - ImpactWithoutCollision: the impulse of Genot & Brogliato (1999) is applied at that instant
///   (impact_without_collision below), recorded as a transition flagged
///   Transition::impact_without_collision, and the run continues in the mode consistent after it.
enum class InconsistentContactResolution : std::uint8_t { Refuse, ImpactWithoutCollision };

inline const char* to_string(InconsistentContactResolution r) {
  switch (r) {
    case InconsistentContactResolution::Refuse:
      return "refuse";
    case InconsistentContactResolution::ImpactWithoutCollision:
      return "impact-without-collision";
  }
  return "?";
}

/// The impulse of an impact without collision at one planar contact (file comment): its two
/// phases and its total, in N s (the scene's force unit times seconds), velocities in m/s.
struct ImpactWithoutCollision {
  double slip_sign = 0.0;                   ///< s = sign(v_t) before the impulse
  double normal_slip = 0.0;                 ///< P_n1, the normal impulse of the slip phase (> 0)
  double tangent_slip = 0.0;                ///< P_t1 = -mu s P_n1
  double normal_velocity_after_slip = 0.0;  ///< v_n1 = v_n + d P_n1 (<= v_n: the compression)
  double normal_stick = 0.0;                ///< P_n2, the normal impulse of the stick phase (>= 0)
  double tangent_stick = 0.0;               ///< P_t2 = -(W_tn / W_tt) P_n2
  double normal = 0.0;                      ///< P_n = P_n1 + P_n2
  double tangent = 0.0;                     ///< P_t = P_t1 + P_t2
};

/// The Darboux-Keller integration of the impulse of an impact without collision (file comment).
/// `W`: the contact's 2 x 2 Delassus matrix J M^{-1} J^T, rows (normal, tangent), in 1/kg (scene
/// units), symmetric positive semidefinite; `mu` > 0: its friction coefficient; `v_n`, `v_t`: its
/// normal and tangential velocity before the impulse (v_n zero up to round-off, v_t != 0).
/// Precondition: the slip is inconsistent, d = W_nn - mu s W_nt <= 0 (up to 1e-12 relative).
/// @throws InvalidArgument on a non-finite input, mu <= 0, v_t = 0, W_tt <= 0 or a consistent
/// slip (d > 0: no impulse is called for); ContactProblemFailure where the phases the derivation
/// guarantees for a positive semidefinite W do not happen (the slip does not stop, or the stick is
/// outside the friction cone: a W that is not symmetric positive semidefinite).
inline ImpactWithoutCollision impact_without_collision(const Eigen::Matrix2d& W, double mu, double v_n, double v_t) {
  SALTUS_REQUIRE(W.allFinite() && std::isfinite(mu) && std::isfinite(v_n) && std::isfinite(v_t),
                 "impact without collision: non-finite input (W = [", W.row(0), "; ", W.row(1), "], mu = ", mu,
                 ", v_n = ", v_n, ", v_t = ", v_t, ")");
  SALTUS_REQUIRE(mu > 0, "impact without collision: mu must be > 0, got ", mu);
  SALTUS_REQUIRE(v_t != 0, "impact without collision: the contact does not slide (v_t = 0)");
  SALTUS_REQUIRE(W(1, 1) > 0, "impact without collision: W_tt must be > 0, got ", W(1, 1));
  ImpactWithoutCollision r;
  const double s = v_t > 0 ? 1.0 : -1.0;
  r.slip_sign = s;
  const double d = W(0, 0) - mu * s * W(0, 1);
  SALTUS_REQUIRE(d <= 1e-12 * (std::abs(W(0, 0)) + mu * std::abs(W(0, 1))),
                 "impact without collision: the slip is consistent (W_nn - mu s W_nt = ", d,
                 " > 0: a nonnegative normal force exists), no impulse is called for");
  // Phase 1: slip until v_t = 0.
  const double c = W(1, 0) - mu * s * W(1, 1);
  if (!(s * c < 0))
    throw ContactProblemFailure(detail::concat(
        "impact without collision: the slip phase does not stop the slip (dv_t/dP_n = W_tn - mu s W_tt = ", c,
        " has the sign of v_t = ", v_t, "): W = [", W.row(0), "; ", W.row(1),
        "] is not symmetric positive semidefinite, for which the derivation shows it stops"));
  r.normal_slip = -v_t / c;
  r.tangent_slip = -mu * s * r.normal_slip;
  r.normal_velocity_after_slip = v_n + d * r.normal_slip;
  // Phase 2: stick until v_n = 0.
  const double ratio = W(1, 0) / W(1, 1);
  if (!(std::abs(ratio) <= mu * (1 + 1e-12)))
    throw ContactProblemFailure(
        detail::concat("impact without collision: sticking after the slip needs |W_tn / W_tt| = ", std::abs(ratio),
                       " <= mu = ", mu, " (a reverse slip would follow): W = [", W.row(0), "; ", W.row(1),
                       "] is not symmetric positive semidefinite, for which the derivation shows stick is possible"));
  const double rate = W(0, 0) - W(0, 1) * ratio;  // det W / W_tt
  if (r.normal_velocity_after_slip < 0) {
    if (!(rate > 0))
      throw ContactProblemFailure(detail::concat(
          "impact without collision: the stick phase cannot bring the normal velocity ", r.normal_velocity_after_slip,
          " back to zero (det W / W_tt = ", rate, " <= 0: the contact's normal and tangent rows are dependent)"));
    r.normal_stick = -r.normal_velocity_after_slip / rate;
    r.tangent_stick = -ratio * r.normal_stick;
  }
  r.normal = r.normal_slip + r.normal_stick;
  r.tangent = r.tangent_slip + r.tangent_stick;
  return r;
}

}  // namespace saltus
