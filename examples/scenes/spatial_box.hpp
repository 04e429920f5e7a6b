// A rigid box in space above flat ground, with its eight corners as contacts with spatial
// (disk) Coulomb friction: the hard case of redundant contacts (flat on four corners: 4 normal and
// 8 tangential rows for 6 degrees of freedom).
//
//   q = (x, y, z, roll, pitch, yaw)   centre position [m]; Z-Y-X Euler angles [rad] with
//                                     R = Rz(yaw) Ry(pitch) Rx(roll)
// The body angular velocity is omega_b = E(roll, pitch) (roll', pitch', yaw')', with
//   E = [1 0 -sin(pitch); 0 cos(roll) sin(roll) cos(pitch); 0 -sin(roll) cos(roll) cos(pitch)],
// so M = diag(m I_3, E^T I_b E), and h = c(q, v) + (0, 0, m g, 0, 0, 0) with the Coriolis and
// centrifugal terms c derived from M by automatic differentiation (coriolis_from_mass_matrix).
// Euler angles are singular at pitch = +-pi/2 (E loses rank and M is no longer SPD, which
// evaluate_dynamics reports as NonSpdMassMatrix): use the scene away from that, as all the
// landing, sliding and tipping motions of the tests do (|pitch| < 1.2).
// The box is unactuated (nu = 0): it is the impact and friction stress case, not a control one.
#pragma once

#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/instantiate.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/sensitivity/instantiate.hpp>

#include <array>
#include <cmath>
#include <random>
#include <string>

namespace saltus::scenes {

struct SpatialBoxParameters {
  double mass = 2.0;                        ///< kg
  std::array<double, 3> size{0.4, 0.3, 0.2};  ///< m, edge lengths along the body x, y, z
  double gravity = 9.81;                    ///< m/s^2
  double mu = 0.5;                          ///< corner-ground Coulomb coefficient
  double restitution = 0.0;
};

class SpatialBox {
 public:
  static constexpr int nq = 6, nu = 0, nc = 8;
  using Parameters = SpatialBoxParameters;
  static constexpr const char* name = "spatial_box";

  explicit SpatialBox(Parameters p = {}) : p_(p) {
    for (int i = 0; i < nc; ++i) {
      corners_[i] = ContactSpec{"corner" + std::to_string(i), Friction::Spatial, p.mu, p.restitution};
      corner_body_[i] = {(i & 1 ? 0.5 : -0.5) * p.size[0], (i & 2 ? 0.5 : -0.5) * p.size[1],
                         (i & 4 ? 0.5 : -0.5) * p.size[2]};
    }
    const double a = p.size[0], b = p.size[1], c = p.size[2];
    inertia_ = {p.mass * (b * b + c * c) / 12.0, p.mass * (a * a + c * c) / 12.0, p.mass * (a * a + b * b) / 12.0};
  }

  const Parameters& parameters() const { return p_; }
  const ContactSpec& contact(int i) const { return corners_[i]; }
  /// Corner i in the body frame; corners 0-3 are the bottom face (body z = -c/2).
  const std::array<double, 3>& corner_in_body(int i) const { return corner_body_[i]; }

  template <class T>
  MatT<T, 3, 3> rotation(const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const T cr = cos(q[3]), sr = sin(q[3]), cp = cos(q[4]), sp = sin(q[4]), cy = cos(q[5]), sy = sin(q[5]);
    MatT<T, 3, 3> R;
    R << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
        sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
        -sp, cp * sr, cp * cr;
    return R;
  }
  /// omega_body = E(q) (roll', pitch', yaw')'.
  template <class T>
  MatT<T, 3, 3> euler_rate_map(const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const T cr = cos(q[3]), sr = sin(q[3]), cp = cos(q[4]), sp = sin(q[4]);
    MatT<T, 3, 3> E;
    E << T(1), T(0), -sp,  //
        T(0), cr, sr * cp,  //
        T(0), -sr, cr * cp;
    return E;
  }

  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>& q) const {
    MatT<T, nq, nq> M = MatT<T, nq, nq>::Zero();
    M.template topLeftCorner<3, 3>() = MatT<T, 3, 3>::Identity() * T(p_.mass);
    const MatT<T, 3, 3> E = euler_rate_map(q);
    MatT<T, 3, 3> I = MatT<T, 3, 3>::Zero();
    for (int k = 0; k < 3; ++k) I(k, k) = T(inertia_[k]);
    M.template bottomRightCorner<3, 3>() = E.transpose() * I * E;
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    VecT<T, nq> h = coriolis_from_mass_matrix(*this, q, v);
    h[2] += T(p_.mass * p_.gravity);
    return h;
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nu>();
  }

  template <class T>
  VecT<T, 3> corner(int i, const VecT<T, nq>& q) const {
    const VecT<T, 3> r{T(corner_body_[i][0]), T(corner_body_[i][1]), T(corner_body_[i][2])};
    return q.template head<3>() + rotation(q) * r;
  }
  template <class T>
  T gap(int i, const VecT<T, nq>& q) const {
    return corner(i, q)[2];
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, nq>& q) const {
    return corner(i, q).template head<2>();
  }
  template <class T>
  T potential_energy(const VecT<T, nq>& q) const {
    return T(p_.mass * p_.gravity) * q[2];
  }

  /// Resting on the ground: flat on the bottom face (a quarter of the draws: four contacts, a
  /// singular Delassus matrix), on a bottom edge (two contacts), or on a single corner.
  template <class Rng>
  Vec<nq> touching_configuration(Rng& rng) const {
    std::uniform_real_distribution<double> pos(-1.0, 1.0), ang(-0.6, 0.6), yaw(-3.0, 3.0), coin(0.0, 1.0);
    Vec<nq> q(pos(rng), pos(rng), 1.0, 0.0, 0.0, yaw(rng));
    const double c = coin(rng);
    if (c < 0.25) {
      // flat
    } else if (c < 0.5) {
      q[3] = ang(rng);  // roll only: an edge parallel to the body x axis touches
    } else {
      q[3] = ang(rng);
      q[4] = ang(rng);
    }
    double lowest = 1e300;
    for (int i = 0; i < nc; ++i) lowest = std::min(lowest, gap(i, q));
    q[2] -= lowest;
    return q;
  }

 private:
  Parameters p_;
  std::array<ContactSpec, nc> corners_;
  std::array<std::array<double, 3>, nc> corner_body_{};
  std::array<double, 3> inertia_{};
};

}  // namespace saltus::scenes

// Compiled once, in spatial_box.cpp (saltus_scenes): a program that includes this header links it.
SALTUS_DECLARE_SCENE(saltus::scenes::SpatialBox)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::SpatialBox)
