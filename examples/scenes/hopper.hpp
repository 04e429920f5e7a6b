// The planar one-legged hopping robot Capler (time-freezing paper, Section 6; model data as
// given in the Saltus issue for the hopper): a base at the hip that translates without rotating,
// a thigh and a shank driven by direct-drive motors at the hip and the knee, and the foot as the
// single contact with the ground (planar Coulomb friction, mu = 0.8).
//
//   q = (x, z, phi_hip, phi_knee)     x, z: hip position [m]; phi_hip: thigh angle from the
//                                     downward vertical, counter-clockwise [rad]; phi_knee: shank
//                                     angle relative to the thigh [rad]
//   u = (tau_hip, tau_knee)           [N m]
//
// Derivation (Lagrange's equations, written out here and checked against automatic
// differentiation of the same Lagrangian in tests/scene_battery.hpp, the scene batteries):
//   with s1 = sin phi_hip, c1 = cos phi_hip, s12 = sin(phi_hip + phi_knee), c12 = cos(...),
//   thigh centre of mass  p1 = (x + d1 s1, z - d1 c1),
//   knee                  pk = (x + l1 s1, z - l1 c1),
//   shank centre of mass  p2 = pk + d2 (s12, -c12),       foot pf = pk + l2 (s12, -c12),
//   T = 1/2 m_b |(x', z')|^2 + 1/2 m1 |p1'|^2 + 1/2 I1 w1^2 + 1/2 m2 |p2'|^2 + 1/2 I2 w12^2,
//       w1 = phi_hip', w12 = phi_hip' + phi_knee',
//   V = g (m_b z + m1 (z - d1 c1) + m2 (z - l1 c1 - d2 c12)).
//   With m = m_b + m1 + m2, a = m1 d1 + m2 l1, b = m2 d2:
//   M = [ m      0      a c1 + b c12                      b c12
//         0      m      a s1 + b s12                      b s12
//         .      .      m1 d1^2 + I1 + m2 (l1^2 + d2^2 + 2 l1 d2 cos phi_knee) + I2
//                                                         m2 (d2^2 + l1 d2 cos phi_knee) + I2
//         .      .      .                                 m2 d2^2 + I2 ]
//   h = d/dt(dT/dv) - M v' - dT/dq + dV/dq:
//   h_x    = -a s1 w1^2 - b s12 w12^2
//   h_z    =  a c1 w1^2 + b c12 w12^2 + m g
//   h_hip  = -m2 l1 d2 sin(phi_knee) (2 w1 phi_knee' + phi_knee'^2) + g (a s1 + b s12)
//   h_knee =  m2 l1 d2 sin(phi_knee) w1^2 + g b s12
//   S = [0 0; 0 0; 1 0; 0 1]: the hip torque acts on phi_hip (the base does not rotate), the
//   knee torque on phi_knee.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/sensitivity/instantiate.hpp>

#include <cmath>
#include <random>

namespace saltus::scenes {

struct HopperParameters {
  double base_mass = 3.975;    ///< kg, hip/base (issue data)
  double thigh_mass = 1.782;   ///< kg
  double shank_mass = 0.548;   ///< kg
  double thigh_length = 0.2;   ///< m, hip to knee
  double shank_length = 0.2;   ///< m, knee to foot
  double thigh_com = 0.016;    ///< m, from the hip along the thigh
  double shank_com = 0.1;      ///< m, from the knee along the shank
  double thigh_inertia = 0.001;   ///< kg m^2 about the thigh's centre of mass
  double shank_inertia = 0.0032;  ///< kg m^2 about the shank's centre of mass
  double gravity = 9.81;       ///< m/s^2
  double mu = 0.8;             ///< foot-ground Coulomb coefficient (time-freezing paper, Sec. 6)
  double restitution = 0.0;
};

class Hopper {
 public:
  static constexpr int nq = 4, nu = 2, nc = 1;
  using Parameters = HopperParameters;
  static constexpr const char* name = "hopper";

  explicit Hopper(Parameters p = {}) : p_(p), foot_{"foot", Friction::Planar, p.mu, p.restitution} {}

  const Parameters& parameters() const { return p_; }
  const ContactSpec& contact(int) const { return foot_; }

  double total_mass() const { return p_.base_mass + p_.thigh_mass + p_.shank_mass; }

  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const double m1 = p_.thigh_mass, m2 = p_.shank_mass, l1 = p_.thigh_length;
    const double d1 = p_.thigh_com, d2 = p_.shank_com;
    const double a = m1 * d1 + m2 * l1, b = m2 * d2;
    const T c1 = cos(q[2]), s1 = sin(q[2]), c12 = cos(q[2] + q[3]), s12 = sin(q[2] + q[3]);
    const T ck = cos(q[3]);
    MatT<T, nq, nq> M;
    M(0, 0) = T(total_mass());
    M(1, 1) = T(total_mass());
    M(0, 1) = T(0);
    M(0, 2) = a * c1 + b * c12;
    M(0, 3) = b * c12;
    M(1, 2) = a * s1 + b * s12;
    M(1, 3) = b * s12;
    M(2, 2) = m1 * d1 * d1 + p_.thigh_inertia + m2 * (l1 * l1 + d2 * d2 + 2.0 * l1 * d2 * ck) + p_.shank_inertia;
    M(2, 3) = m2 * (d2 * d2 + l1 * d2 * ck) + p_.shank_inertia;
    M(3, 3) = T(m2 * d2 * d2 + p_.shank_inertia);
    for (int i = 0; i < nq; ++i)
      for (int j = 0; j < i; ++j) M(i, j) = M(j, i);
    return M;
  }

  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    using std::cos;
    using std::sin;
    const double m1 = p_.thigh_mass, m2 = p_.shank_mass, l1 = p_.thigh_length;
    const double d1 = p_.thigh_com, d2 = p_.shank_com, g = p_.gravity;
    const double a = m1 * d1 + m2 * l1, b = m2 * d2;
    const T c1 = cos(q[2]), s1 = sin(q[2]), c12 = cos(q[2] + q[3]), s12 = sin(q[2] + q[3]);
    const T sk = sin(q[3]);
    const T w1 = v[2], wk = v[3], w12 = v[2] + v[3];
    VecT<T, nq> h;
    h[0] = -a * s1 * w1 * w1 - b * s12 * w12 * w12;
    h[1] = a * c1 * w1 * w1 + b * c12 * w12 * w12 + total_mass() * g;
    h[2] = -m2 * l1 * d2 * sk * (2.0 * w1 * wk + wk * wk) + g * (a * s1 + b * s12);
    h[3] = m2 * l1 * d2 * sk * w1 * w1 + g * b * s12;
    return h;
  }

  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nu> S = MatT<T, nq, nu>::Zero();
    S(2, 0) = T(1);
    S(3, 1) = T(1);
    return S;
  }

  /// Foot position (x, z).
  template <class T>
  VecT<T, 2> foot(const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const T a1 = q[2], a12 = q[2] + q[3];
    return VecT<T, 2>(q[0] + p_.thigh_length * sin(a1) + p_.shank_length * sin(a12),
                      q[1] - p_.thigh_length * cos(a1) - p_.shank_length * cos(a12));
  }
  /// Knee position (x, z).
  template <class T>
  VecT<T, 2> knee(const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    return VecT<T, 2>(q[0] + p_.thigh_length * sin(q[2]), q[1] - p_.thigh_length * cos(q[2]));
  }

  template <class T>
  T gap(int, const VecT<T, nq>& q) const {
    return foot(q)[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const {
    return VecT<T, 2>(foot(q)[0], T(0));
  }

  template <class T>
  T potential_energy(const VecT<T, nq>& q) const {
    using std::cos;
    const double m1 = p_.thigh_mass, m2 = p_.shank_mass;
    const T z1 = q[1] - p_.thigh_com * cos(q[2]);
    const T z2 = q[1] - p_.thigh_length * cos(q[2]) - p_.shank_com * cos(q[2] + q[3]);
    return p_.gravity * (p_.base_mass * q[1] + m1 * z1 + m2 * z2);
  }

  /// Kinetic energy written from the body velocities (independent of M, for the tests).
  template <class T>
  T kinetic_energy_from_bodies(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    using std::cos;
    using std::sin;
    const T w1 = v[2], w12 = v[2] + v[3];
    const T c1 = cos(q[2]), s1 = sin(q[2]), c12 = cos(q[2] + q[3]), s12 = sin(q[2] + q[3]);
    const T p1x = v[0] + p_.thigh_com * c1 * w1, p1z = v[1] + p_.thigh_com * s1 * w1;
    const T p2x = v[0] + p_.thigh_length * c1 * w1 + p_.shank_com * c12 * w12;
    const T p2z = v[1] + p_.thigh_length * s1 * w1 + p_.shank_com * s12 * w12;
    return 0.5 * p_.base_mass * (v[0] * v[0] + v[1] * v[1]) + 0.5 * p_.thigh_mass * (p1x * p1x + p1z * p1z) +
           0.5 * p_.thigh_inertia * w1 * w1 + 0.5 * p_.shank_mass * (p2x * p2x + p2z * p2z) +
           0.5 * p_.shank_inertia * w12 * w12;
  }

  /// A random leg posture with the foot on the ground.
  template <class Rng>
  Vec<nq> touching_configuration(Rng& rng) const {
    std::uniform_real_distribution<double> hip(-0.8, 0.8), knee(-1.4, 1.4), x(-1.0, 1.0);
    Vec<nq> q(x(rng), 0.0, hip(rng), knee(rng));
    q[1] -= foot(q)[1];
    return q;
  }

 private:
  Parameters p_;
  ContactSpec foot_;
};

}  // namespace saltus::scenes

// Compiled once, in hopper.cpp (saltus_scenes): a program that includes this header links it.
SALTUS_DECLARE_SCENE(saltus::scenes::Hopper)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::Hopper)
