// The guiding example of the time-freezing paper (Nurkanovic et al. 2023, Example 1, eq. 5):
// a point mass in the vertical plane above a horizontal table, pushed by a thrust u.
//   q = (q1, q2): horizontal position and height [m];  u = (u1, u2): thrust [N]
//   m q'' = (0, -m g) + u + (0, 1) lambda_n,   0 <= lambda_n _|_ q2 >= 0.
// Example 1 is frictionless; planar Coulomb friction can be switched on for tests.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/sensitivity/instantiate.hpp>

#include <array>
#include <random>

namespace saltus::scenes {

struct PointMassParameters {
  double mass = 1.0;         ///< kg (Example 1)
  double gravity = 9.81;     ///< m/s^2 (Example 1)
  Friction friction = Friction::None;  ///< Example 1: frictionless
  double mu = 0.0;           ///< Coulomb coefficient when friction is on
  double restitution = 0.0;  ///< inelastic table (eq. 5d)
};

class PointMass {
 public:
  static constexpr int nq = 2, nu = 2, nc = 1;
  using Parameters = PointMassParameters;
  static constexpr const char* name = "point_mass";

  explicit PointMass(Parameters p = {}) : p_(p), table_{"table", p.friction, p.mu, p.restitution} {}

  const Parameters& parameters() const { return p_; }
  const ContactSpec& contact(int) const { return table_; }

  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nq>::Identity() * T(p_.mass);
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>(T(0), T(p_.mass * p_.gravity));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nu>::Identity();
  }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const {
    return q[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const {
    return VecT<T, 2>(q[0], T(0));
  }
  template <class T>
  T potential_energy(const VecT<T, nq>& q) const {
    return T(p_.mass * p_.gravity) * q[1];
  }

  /// A configuration on the table (the contact touching) for random impact tests.
  template <class Rng>
  Vec<nq> touching_configuration(Rng& rng) const {
    std::uniform_real_distribution<double> x(-1.0, 1.0);
    return Vec<nq>(x(rng), 0.0);
  }

 private:
  Parameters p_;
  ContactSpec table_;
};

}  // namespace saltus::scenes

// Compiled once, in point_mass.cpp (saltus_scenes): a program that includes this header links it.
SALTUS_DECLARE_SCENE(saltus::scenes::PointMass)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::PointMass)
