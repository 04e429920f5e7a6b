// The time-freezing system of a planar Scene (time-freezing paper, Sections 3-4: regions eq. 14
// and 25, auxiliary dynamics eq. 16 and eq. 24 with a_t = mu a_n, the step-function DCS eqs.
// 31-32), written for any number of contacts.
//
// State y = (q, v, t, L, g) in R^{2 nq + 2 + nc}: configuration, velocity, the clock t (physical
// time), the cost quadrature L (the running cost integrated over physical time only, eq. 29: it
// runs with the clock) and the integrated gaps g (one per contact, below). Inputs u in R^nu.
//
// INTEGRATED GAPS (this library's addition, not in the paper). g_i' = Theta J_n,i(q) v [m per unit
// numerical time; times s, eq. 33] with g_i(0) = gap_i(q0) [m]: since q' = Theta v in every region,
// g_i = gap_i(q) along every exact solution; a discretisation integrates g with the same
// collocation as q, so g_i differs from gap_i(q) by the discretisation error only. Why carry it: in a stance the exact solution sits
// on gap = 0 AND J_n v = 0 (the auxiliary field freezes q, so an impact ends ON the surface, and
// the Filippov solution then slides along J_n v = 0). A collocation step that holds both at every
// stage point imposes two conditions where the continuous problem has one; for a gap nonlinear
// in q they disagree at the order of the step's local error (the gap's higher derivatives along
// the motion), so the discrete problem with both exactly zero has no solution in a moving stance
// (derivation in fesd.hpp, "INTEGRATED GAP"). g's stage values are g_start + h sum_l a_rl s Theta_l
// J_n v_l, which vanish whenever the stage values of J_n v do: the two conditions then agree
// exactly, as they do for a gap linear in q. FesdOptions::switching.integrated_gap chooses which gap the
// switching functions read.
//
// ONE CONTACT i (eq. 25). Switching functions c_i = (gap_i(q), J_n,i(q) v, J_t,i(q) v): gap, normal
// and tangential velocity (J = the gradients of the scene's gap and tangent position). With the
// step functions alpha_i,k in [0, 1] of c_i,k (alpha = 1 where c > 0, eq. 31):
//     theta_i^free  = alpha_i1 + (1 - alpha_i1) alpha_i2        (R1: open, or closed and leaving)
//     theta_i^+     = (1 - alpha_i1)(1 - alpha_i2) alpha_i3      (R2: closing, sliding with v_t > 0)
//     theta_i^-     = (1 - alpha_i1)(1 - alpha_i2)(1 - alpha_i3) (R3: closing, v_t < 0)
// (theta_i^free + theta_i^+ + theta_i^- = 1; eq. 32). The auxiliary dynamics of contact i act on
// the velocity only, with the clock frozen (eq. 16, 24, a_t = mu a_n):
//     M(q) v' = a_n (J_n,i - mu_i J_t,i)  in R2,   a_n (J_n,i + mu_i J_t,i)  in R3,   q' = 0, t' = 0.
// A frictionless contact has no tangential switching function: its c_i3 is the constant 1 (so
// alpha_i3 = 1 and theta_i^- = 0 at every solution) and mu_i = 0; this keeps the compile-time
// layout of 3 switching functions per contact without adding switches at v_t = 0.
//
// SEVERAL CONTACTS (the construction of this library; the paper treats one contact). The product
// space of the contacts' regions has 3^nc regions; in the region where the set A of contacts is
// in an auxiliary region the field is the SUM of their auxiliary fields (each contact pushes its
// own normal velocity up at rate a_n, through the coupling of M^-1), and the ODE field with the
// clock running only where A is empty. Weighting each region by the product of the contacts'
// thetas (the multi-affine Heaviside DCS) and summing, the products collapse because
// theta_i^free + theta_i^+ + theta_i^- = 1:
//     M(q) v' = Theta (S u - h) + a_n sum_i [ theta_i^+ (J_n,i - mu_i J_t,i) + theta_i^- (J_n,i + mu_i J_t,i) ],
//     q' = Theta v,   t' = Theta,   L' = Theta l(x, u),        Theta = prod_i theta_i^free.
// So physical time runs only when no contact is in an auxiliary region. When two contacts are in
// their auxiliary regions at once both push together with the clock frozen: a frozen-time
// resolution of a simultaneous impact. A contact whose normal velocity reaches 0 first leaves its
// auxiliary region; if the other contact's push, through J_n,i' M^-1 J_n,j, drives it negative
// again it re-enters: the Filippov solution slides on J_n,i v = 0, i.e. that contact is held at
// zero normal velocity while the other one finishes. For a symmetric flat landing (the plank-box)
// both normal velocities reach zero together. The frozen phase ends when every contact has
// J_n v >= 0, and its outcome satisfies Signorini's conditions at the velocity level; in general
// it need not equal the impact law of the event-driven simulator (dynamics/impact_law.hpp: a
// single LCP), so the two are compared on scenes, not assumed equal.
//
// With the speed of time s >= 1 (eq. 33) every field is multiplied by s.
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>

#include <Eigen/Core>

#include <array>
#include <cmath>

namespace saltus::timefreezing {

/// The time-freezing reformulation of a planar scene (see the file comment).
/// Preconditions (checked, InvalidArgument): every contact frictionless or planar (spatial
/// friction needs eq. 26's regularised field, not built), restitution e_n = 0 (elastic
/// time-freezing is not built), a_n > 0 and finite.
template <Scene S>
class TimeFreezingSystem {
 public:
  static constexpr int nq = S::nq;
  static constexpr int nu = S::nu;
  static constexpr int nc = S::nc;
  static constexpr int nx = 2 * nq;
  /// y = (q, v, t, L, g).
  static constexpr int ny = 2 * nq + 2 + nc;
  static constexpr int clock_index = 2 * nq;
  static constexpr int cost_index = 2 * nq + 1;
  /// Index of contact 0's integrated gap g_0 in y (contact i: gap_state_index + i).
  static constexpr int gap_state_index = 2 * nq + 2;
  /// Three switching functions per contact: gap, normal velocity, tangential velocity.
  static constexpr int n_switch = 3 * nc;

  /// a_n: the auxiliary normal acceleration (paper's a_n; units of J_n' M^-1 J_n a_n are
  /// m/s^2 of the contact's normal velocity per unit numerical time when J_n is a unit normal).
  TimeFreezingSystem(const S& scene, double auxiliary_acceleration) : scene_(scene), a_n_(auxiliary_acceleration) {
    validate_scene(scene);
    SALTUS_REQUIRE(std::isfinite(a_n_) && a_n_ > 0.0,
                   "time-freezing: the auxiliary acceleration a_n must be finite and > 0, got ", a_n_);
    for (int i = 0; i < nc; ++i) {
      const ContactSpec& c = scene.contact(i);
      SALTUS_REQUIRE(c.friction != Friction::Spatial, "time-freezing: contact '", c.name,
                     "' has spatial friction; the time-freezing system supports frictionless and planar contacts");
      SALTUS_REQUIRE(c.restitution == 0.0, "time-freezing: contact '", c.name, "' has restitution e_n = ",
                     c.restitution, "; the inelastic time-freezing system needs e_n = 0");
      mu_[i] = c.friction == Friction::Planar ? c.mu : 0.0;
      planar_[i] = c.friction == Friction::Planar;
    }
  }

  const S& scene() const { return scene_; }
  double auxiliary_acceleration() const { return a_n_; }
  bool has_friction(int i) const { return planar_[i]; }

  /// c(q, v) (size 3 nc): per contact (gap, J_n v, J_t v); the third is 1 for a frictionless one.
  template <class T>
  VecT<T, n_switch> switching_functions(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    using D = ad::Dual<T, 1>;
    const VecT<D, nq> qd = seeded_along<T>(q, v);
    VecT<T, n_switch> c;
    for (int i = 0; i < nc; ++i) {
      const D g = scene_.template gap<D>(i, qd);
      c[3 * i] = g.value();
      c[3 * i + 1] = g.derivatives()[0];
      if (planar_[i]) {
        const VecT<D, 2> tp = scene_.template tangent_position<D>(i, qd);
        c[3 * i + 2] = tp[0].derivatives()[0];
      } else {
        c[3 * i + 2] = T(1.0);
      }
    }
    return c;
  }

  /// J_n,i(q) v of every contact (size nc; units of the gaps per second): the integrated gaps'
  /// field is Theta times these.
  template <class T>
  VecT<T, (nc > 0 ? nc : 1)> normal_velocities(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    VecT<T, (nc > 0 ? nc : 1)> out;
    out.setZero();
    const VecT<ad::Dual<T, 1>, nq> qd = seeded_along<T>(q, v);
    for (int i = 0; i < nc; ++i) out[i] = scene_.template gap<ad::Dual<T, 1>>(i, qd).derivatives()[0];
    return out;
  }

  /// Contact i's closing weight beta_i = (1 - alpha_i1)(1 - alpha_i2) = theta_i^+ + theta_i^-:
  /// the auxiliary dynamics' share of the contact (alpha of size 3 nc, 0 <= i < nc).
  template <class T, class Alpha>
  static T closing_weight(const Alpha& alpha, int i) {
    return T(T(1.0 - alpha[3 * i]) * T(1.0 - alpha[3 * i + 1]));
  }

  /// Theta_i^free of each contact and Theta = prod_i theta_i^free (file comment).
  template <class T>
  static T ode_weight(const VecT<T, n_switch>& alpha) {
    T theta(1.0);
    for (int i = 0; i < nc; ++i) {
      const T& a1 = alpha[3 * i];
      const T& a2 = alpha[3 * i + 1];
      theta = T(theta * T(a1 + T(T(1.0 - a1) * a2)));
    }
    return theta;
  }

  /// The right-hand side of M(q) v' in the time-freezing DCS at step values alpha (size nq):
  /// Theta (S u - h) + a_n sum_i [theta_i^+ (J_n - mu J_t) + theta_i^- (J_n + mu J_t)].
  template <class T>
  VecT<T, nq> generalised_force(const VecT<T, nq>& q, const VecT<T, nq>& v, const VecT<T, nu>& u,
                                const VecT<T, n_switch>& alpha) const {
    VecT<T, (nc > 0 ? nc : 1)> closing;
    for (int i = 0; i < nc; ++i) closing[i] = closing_weight<T>(alpha, i);
    return force_from_weights<T>(q, v, u, ode_weight<T>(alpha), closing, alpha);
  }

 private:
  static constexpr int kinematics_stride = 2 * nq + 1;
  static constexpr int kinematics_size = nc > 0 ? nc * kinematics_stride : 1;

  // q seeded with the direction v: functions of it carry their directional derivative along v
  // (J v for the gap and the tangent position), one more AD level with one direction.
  template <class T>
  static VecT<ad::Dual<T, 1>, nq> seeded_along(const VecT<T, nq>& q, const VecT<T, nq>& v) {
    VecT<ad::Dual<T, 1>, nq> qd;
    for (int k = 0; k < nq; ++k) qd[k] = ad::Dual<T, 1>(q[k], Eigen::Matrix<T, 1, 1>(v[k]));
    return qd;
  }

  // Theta (S u - h) + a_n sum_i beta_i [alpha_i3 (J_n - mu J_t) + (1 - alpha_i3)(J_n + mu J_t)].
  template <class T>
  VecT<T, nq> force_from_weights(const VecT<T, nq>& q, const VecT<T, nq>& v, const VecT<T, nu>& u, const T& theta,
                                 const VecT<T, (nc > 0 ? nc : 1)>& closing, const VecT<T, n_switch>& alpha) const {
    VecT<T, nq> f = -scene_.template bias<T>(q, v);
    if constexpr (nu > 0) f += scene_input_matrix<S, T>(scene_, q) * u;
    f *= theta;
    if constexpr (nc > 0) {
      const VecT<T, kinematics_size> k = kinematics_direct<T>(q);
      for (int i = 0; i < nc; ++i) {
        const T plus = T(closing[i] * alpha[3 * i + 2]);
        const T minus = T(closing[i] * T(1.0 - alpha[3 * i + 2]));
        f += T(a_n_ * T(plus + minus)) * k.template segment<nq>(i * kinematics_stride + 1);
        if (planar_[i]) f += T(a_n_ * mu_[i] * T(minus - plus)) * k.template segment<nq>(i * kinematics_stride + 1 + nq);
      }
    }
    return f;
  }

  // Per contact i, at offset i (2 nq + 1): gap_i(q) [m], J_n,i(q) (size nq), J_t,i(q) (size nq;
  // zero for a frictionless contact): the gradients by one more AD level along the nq coordinates.
  template <class R>
  VecT<R, kinematics_size> kinematics_direct(const VecT<R, nq>& q) const {
    VecT<R, kinematics_size> k;
    k.setZero();
    if constexpr (nc > 0) {
      using D = ad::Dual<R, nq>;
      VecT<D, nq> qd;
      for (int a = 0; a < nq; ++a) qd[a] = ad::seed<nq>(q[a], a);
      for (int i = 0; i < nc; ++i) {
        const int base = i * kinematics_stride;
        const D g = scene_.template gap<D>(i, qd);
        k[base] = g.value();
        k.template segment<nq>(base + 1) = g.derivatives();
        if (planar_[i]) k.template segment<nq>(base + 1 + nq) = scene_.template tangent_position<D>(i, qd)[0].derivatives();
      }
    }
    return k;
  }

  S scene_;
  double a_n_;
  std::array<double, (nc > 0 ? nc : 1)> mu_{};
  std::array<bool, (nc > 0 ? nc : 1)> planar_{};
};

}  // namespace saltus::timefreezing
