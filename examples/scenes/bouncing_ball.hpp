// A ball falling vertically onto the ground: the simplest impact, and with restitution e_n > 0
// the classic Zeno accumulation of bounces.
//   q = height of the ball's lowest point [m];  m q'' = -m g + lambda_n,  0 <= lambda_n _|_ q >= 0,
//   q'+ = -e_n q'- at each impact.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/sensitivity/instantiate.hpp>

#include <random>

namespace saltus::scenes {

struct BouncingBallParameters {
  double mass = 0.1;          ///< kg
  double gravity = 9.81;      ///< m/s^2
  double restitution = 0.5;   ///< Newton coefficient e_n
};

class BouncingBall {
 public:
  static constexpr int nq = 1, nu = 0, nc = 1;
  using Parameters = BouncingBallParameters;
  static constexpr const char* name = "bouncing_ball";

  explicit BouncingBall(Parameters p = {}) : p_(p), ground_{"ground", Friction::None, 0.0, p.restitution} {}

  const Parameters& parameters() const { return p_; }
  const ContactSpec& contact(int) const { return ground_; }

  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nq>::Constant(T(p_.mass));
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>::Constant(T(p_.mass * p_.gravity));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nu>();
  }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const {
    return q[0];
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>&) const {
    return VecT<T, 2>::Zero();
  }
  template <class T>
  T potential_energy(const VecT<T, nq>& q) const {
    return T(p_.mass * p_.gravity) * q[0];
  }

  template <class Rng>
  Vec<nq> touching_configuration(Rng&) const {
    return Vec<nq>::Zero();
  }

 private:
  Parameters p_;
  ContactSpec ground_;
};

}  // namespace saltus::scenes

// Compiled once, in bouncing_ball.cpp (saltus_scenes): a program that includes this header links it.
SALTUS_DECLARE_SCENE(saltus::scenes::BouncingBall)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::BouncingBall)
